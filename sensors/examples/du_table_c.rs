//! Prints the firmware's du table (`firmware/du_table.c`) from [`sensors::DU_TABLE`], so the C
//! table and the Rust one have one source: `cargo run -p sensors --example du_table_c >
//! firmware/du_table.c`. The emulator's firmware tests read the table back from the image and
//! compare it with `DU_TABLE`.

fn main() {
    let mut s = String::new();
    s.push_str("/*\n * du_table.c - the distance-unit table (docs/design.md §3.3): du_table[c] is the proximity in du\n");
    s.push_str(
        " * (1 du = 80/255 cm, 255 = 80 cm or more) for the 8-bit A/D code c = ADC10 >> 2.\n",
    );
    s.push_str(
        " * Generated from sensors::DU_TABLE by `cargo run -p sensors --example du_table_c`;\n",
    );
    s.push_str(" * do not edit (a test compares the image's table with the Rust one).\n */\n");
    s.push_str("#include \"h8.h\"\n\nconst u8 du_table[256] = {\n");
    for row in sensors::DU_TABLE.chunks(16) {
        let cells: Vec<String> = row.iter().map(|v| format!("{v:3}")).collect();
        s.push_str("    ");
        s.push_str(&cells.join(", "));
        s.push_str(",\n");
    }
    s.push_str("};\n");
    print!("{s}");
}
