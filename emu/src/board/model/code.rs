//! The controller as H8 code: the ROM estimate and the stack depth.
//!
//! The controller runs as Rust, but the chip would run machine code; the ROM it would take is
//! estimated routine by routine from the instructions each routine needs (lengths from the
//! H8/300H instruction formats: one word for register ops, `@ERn`, `@ERn+`, `@aa:8` and
//! Bcc d:8; two for `#xx:16`, `@aa:16`, `@(d:16,ERn)`, JSR `@aa:24` and the bit instructions on
//! `@aa:8`; three for `#xx:32` and `@(d:24,ERn)`; MOV.L memory forms carry one prefix word more).
//! The learner's routines come from `nn_q15`'s cost table ([`nn_q15::LEARNER_ROUTINES`]). The
//! tables the firmware keeps in flash (vectors, the du table, the behaviour table) are data.
//!
//! The stack depth is the deepest chain of calls (return address and the registers each routine
//! saves) plus the tick interrupt's frame on top.

use nn_q15::LEARNER_ROUTINES;

/// A routine as a list of (instruction, length in bytes).
#[derive(Clone, Copy, Debug)]
pub struct Routine {
    /// What the routine does.
    pub name: &'static str,
    /// Its instructions with their lengths.
    pub listing: &'static [(&'static str, u32)],
}

impl Routine {
    /// Code size in bytes.
    #[must_use]
    pub fn bytes(&self) -> u32 {
        self.listing.iter().map(|(_, b)| b).sum()
    }
}

/// The controller's own routines (everything but the learner).
pub const CONTROLLER_ROUTINES: &[Routine] = &[
    Routine {
        name: "reset and hardware set-up",
        listing: &[
            ("MOV.L #H'FFFF10,ER7", 6),
            ("SUB.L ER0,ER0", 2),
            ("MOV.B R0L,@P4DR:8", 2),
            ("MOV.B R0L,@P4DDR:8", 2),
            ("MOV.B R0L,@PBDR:8", 2),
            ("MOV.B #H'C0,R0L", 2),
            ("MOV.B R0L,@P4PCR:8", 2),
            ("MOV.B #H'0F,R0L", 2),
            ("MOV.B R0L,@P2PCR:8", 2),
            ("MOV.B #H'0F,R0L", 2),
            ("MOV.B R0L,@PBDDR:8", 2),
            ("MOV.B #H'23,R0L", 2),
            ("MOV.B R0L,@TCR0:8", 2),
            ("MOV.B R0L,@TCR1:8", 2),
            ("MOV.B R0L,@TCR2:8", 2),
            ("MOV.W #tick,R0", 4),
            ("MOV.W R0,@GRA0:16", 4),
            ("MOV.W #pwm,R0", 4),
            ("MOV.W R0,@GRA1:16", 4),
            ("MOV.W R0,@GRA2:16", 4),
            ("MOV.W R0,@GRB1:16", 4),
            ("MOV.W R0,@GRB2:16", 4),
            ("MOV.B #H'01,R0L", 2),
            ("MOV.B R0L,@TIER0:8", 2),
            ("MOV.B #H'06,R0L", 2),
            ("MOV.B R0L,@TMDR:8", 2),
            ("MOV.B #H'07,R0L", 2),
            ("MOV.B R0L,@TSTR:8", 2),
            ("SUB.L ER0,ER0", 2),
            ("MOV.L ER0,@TICKS:16", 6),
            ("MOV.L ER0,@STEPS:16", 6),
            ("MOV.L ER0,@NEXT:16", 6),
            ("JSR @i2c_bus_clear:24", 4),
            ("JSR @recover:24", 4),
            ("ANDC #H'7F,CCR", 2),
            ("BRA main", 2),
        ],
    },
    Routine {
        name: "main loop and step sequencing",
        listing: &[
            ("SLEEP", 2),
            ("MOV.L @TICKS:16,ER0", 6),
            ("MOV.L @NEXT:16,ER1", 6),
            ("CMP.L ER1,ER0", 2),
            ("BLO main", 2),
            ("ADD.L #ticks_per_step,ER1", 6),
            ("MOV.L ER1,@NEXT:16", 6),
            ("JSR @adc_read:24", 4),
            ("JSR @learner_input:24", 4),
            ("JSR @learner_update:24", 4),
            ("JSR @learner_forward:24", 4),
            ("JSR @motors:24", 4),
            ("MOV.W @SAVE_COUNT:16,R0", 4),
            ("DEC.W #1,R0", 2),
            ("BNE 1f", 2),
            ("JSR @save_record:24", 4),
            ("MOV.W #S,R0", 4),
            ("1: MOV.W R0,@SAVE_COUNT:16", 4),
            ("BRA main", 2),
        ],
    },
    Routine {
        name: "tick interrupt handler",
        listing: &[
            ("PUSH.L ER0", 4),
            ("MOV.B @TSR0:8,R0L", 2),
            ("BCLR #0,R0L", 2),
            ("MOV.B R0L,@TSR0:8", 2),
            ("MOV.L @TICKS:16,ER0", 6),
            ("INC.L #1,ER0", 2),
            ("MOV.L ER0,@TICKS:16", 6),
            ("POP.L ER0", 4),
            ("RTE", 2),
        ],
    },
    Routine {
        name: "A/D scan and du lookup",
        listing: &[
            ("MOV.B #H'3B,R0L", 2),
            ("MOV.B R0L,@ADCSR:8", 2),
            ("1: MOV.B @ADCSR:8,R0L", 2),
            ("BPL 1b", 2),
            ("MOV.B #H'1B,R0L", 2),
            ("MOV.B R0L,@ADCSR:8", 2),
            ("MOV.B @ADDRAH:8,R0L", 2),
            ("EXTU.W R0", 2),
            ("EXTU.L ER0", 2),
            ("MOV.B @(DU:24,ER0),R0L", 8),
            ("MOV.B R0L,@P0:16", 4),
            ("MOV.B @ADDRBH:8,R0L", 2),
            ("EXTU.W R0", 2),
            ("EXTU.L ER0", 2),
            ("MOV.B @(DU:24,ER0),R0L", 8),
            ("MOV.B R0L,@P1:16", 4),
            ("MOV.B @ADDRCH:8,R0L", 2),
            ("EXTU.W R0", 2),
            ("EXTU.L ER0", 2),
            ("MOV.B @(DU:24,ER0),R0L", 8),
            ("MOV.B R0L,@P2:16", 4),
            ("MOV.B @ADDRDH:8,R0L", 2),
            ("EXTU.W R0", 2),
            ("EXTU.L ER0", 2),
            ("MOV.B @(DU:24,ER0),R0L", 8),
            ("MOV.B R0L,@P3:16", 4),
            ("RTS", 2),
        ],
    },
    Routine {
        name: "motor set-up from the behaviour table",
        listing: &[
            ("MOV.B @WIN:16,R0L", 4),
            ("EXTU.W R0", 2),
            ("EXTU.L ER0", 2),
            ("SHLL.L ER0", 2),
            ("SHLL.L ER0", 2),
            ("SHLL.L ER0", 2),
            ("MOV.L #BEHAVIOURS,ER1", 6),
            ("ADD.L ER0,ER1", 2),
            ("MOV.W @ER1+,R0", 2),
            ("MOV.W R0,@GRB1:16", 4),
            ("MOV.W @ER1+,R0", 2),
            ("MOV.W R0,@GRB2:16", 4),
            ("MOV.B @ER1,R0L", 2),
            ("MOV.B R0L,@PBDR:8", 2),
            ("RTS", 2),
        ],
    },
    Routine {
        name: "I2C bit-banging (start, stop, byte out/in, ACK polling, delay)",
        listing: &[
            // pin operations on the DDR shadow in R2L
            ("BSET #7,R2L", 2),
            ("BCLR #7,R2L", 2),
            ("BSET #6,R2L", 2),
            ("BCLR #6,R2L", 2),
            ("MOV.B R2L,@P4DDR:8", 2),
            ("MOV.B @P4DR:8,R0L", 2),
            ("BTST #7,R0L", 2),
            // delay loop
            ("1: DEC.W #1,R3", 2),
            ("BNE 1b", 2),
            ("RTS", 2),
            // start / repeated start / stop: 3 routines of pin operations and delays
            ("JSR @delay:24 (×9)", 36),
            ("MOV.W #n,R3 (×9)", 36),
            ("pin operations (×10)", 20),
            ("RTS (×3)", 6),
            // byte out: 8 bits MSB first, then the ACK bit in
            ("MOV.B #8,R1H", 2),
            ("2: SHLL.B R1L", 2),
            ("BCC 3f", 2),
            ("BCLR #7,R2L", 2),
            ("BRA 4f", 2),
            ("3: BSET #7,R2L", 2),
            ("4: MOV.B R2L,@P4DDR:8", 2),
            ("JSR @clock_pulse:24", 4),
            ("DEC.B R1H", 2),
            ("BNE 2b", 2),
            ("JSR @read_bit:24", 4),
            ("RTS", 2),
            // byte in: 8 bits, then the master's ACK or NACK
            ("MOV.B #8,R1H", 2),
            ("5: JSR @read_bit:24", 4),
            ("ROTXL.B R1L", 2),
            ("DEC.B R1H", 2),
            ("BNE 5b", 2),
            ("JSR @send_bit:24", 4),
            ("RTS", 2),
            // clock pulse and read bit
            ("pin operations (×6)", 12),
            ("JSR @delay:24 (×4)", 16),
            ("MOV.W #n,R3 (×4)", 16),
            ("RTS (×2)", 4),
            // ACK polling
            ("6: JSR @start:24", 4),
            ("MOV.B #control,R1L", 2),
            ("JSR @byte_out:24", 4),
            ("BCC 7f", 2),
            ("DEC.W #1,E1", 2),
            ("BNE 6b", 2),
            ("7: JSR @stop:24", 4),
            ("RTS", 2),
        ],
    },
    Routine {
        name: "record save, recovery and CRC-16",
        listing: &[
            // CRC-16/CCITT-FALSE, bitwise
            ("MOV.W #H'FFFF,R0", 4),
            ("1: MOV.B @ER5+,R1L", 2),
            ("XOR.B R1L,R0H", 2),
            ("MOV.B #8,R2H", 2),
            ("2: SHLL.W R0", 2),
            ("BCC 3f", 2),
            ("XOR.W #H'1021,R0", 4),
            ("3: DEC.B R2H", 2),
            ("BNE 2b", 2),
            ("DEC.W #1,R4", 2),
            ("BNE 1b", 2),
            ("RTS", 2),
            // save: body pages from RAM through the page buffer, then the commit page
            ("MOV.L @SEQ:16,ER0", 6),
            ("MOV.B R0L,R1L ; AND.B #1,R1L", 4),
            ("page loop: JSR @fill_page:24", 4),
            ("JSR @i2c_page_write:24", 4),
            ("JSR @ack_poll:24", 4),
            ("ADD.W #64,R5 ; CMP.W ; BNE", 10),
            ("commit block: 7 MOV.W stores", 28),
            ("JSR @crc16:24 (×2)", 8),
            ("JSR @i2c_page_write:24", 4),
            ("JSR @ack_poll:24", 4),
            ("INC.L #1,ER0 ; MOV.L ER0,@SEQ:16", 8),
            ("RTS", 2),
            // fill the page buffer: EEPMOV.B from the weights
            ("MOV.L #src,ER5 ; MOV.L #PAGE,ER6 ; MOV.B #n,R4L", 14),
            ("EEPMOV.B", 4),
            ("RTS", 2),
            // random read into a buffer
            ("JSR @start:24 ; control ; address high ; address low", 24),
            ("JSR @repeated_start:24 ; control (read)", 12),
            ("byte-in loop with ACK, last NACK", 20),
            ("JSR @stop:24 ; RTS", 6),
            // recovery: both commit blocks, compare sequences, read the newer body, check
            ("read commit A, read commit B", 24),
            ("magic, version, parity, CRC checks", 40),
            ("compare sequences, choose", 12),
            ("read body, CRC, compare with commit", 24),
            ("RTS", 2),
        ],
    },
    Routine {
        name: "fresh random weights (xorshift32)",
        listing: &[
            ("MOV.L #seed,ER0", 6),
            ("MOV.L #W,ER5", 6),
            ("MOV.W #n,R4", 4),
            ("1: MOV.L ER0,ER1", 2),
            ("SHLL.L ER1 (×13)", 26),
            ("XOR.L ER1,ER0", 4),
            ("MOV.L ER0,ER1", 2),
            ("SHLR.L ER1 (×17)", 34),
            ("XOR.L ER1,ER0", 4),
            ("MOV.L ER0,ER1", 2),
            ("SHLL.L ER1 (×5)", 10),
            ("XOR.L ER1,ER0", 4),
            ("MOV.L ER0,ER1", 2),
            ("SHLR.L ER1 (×17)", 34),
            ("SUB.W #H'4000,R1", 4),
            ("MOV.W R1,@ER5", 2),
            ("ADDS #2,ER5", 2),
            ("DEC.W #1,R4", 2),
            ("BNE 1b", 2),
            ("RTS", 2),
        ],
    },
];

/// Bytes of the exception vector table (SPEC §4.1: 61 vectors of 4 bytes).
pub const VECTOR_TABLE_BYTES: u32 = 61 * 4;
/// Bytes of the du table in flash (SPEC §3.3: 256 entries of one byte).
pub const DU_TABLE_BYTES: u32 = 256;
/// Bytes of the behaviour table: per behaviour GRB1, GRB2, the port-B direction byte, padded
/// to 8 bytes so that the row offset is a shift.
pub const BEHAVIOUR_TABLE_BYTES: u32 = 4 * 8;

/// One line of the ROM estimate.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RomLine {
    /// What it is.
    pub name: &'static str,
    /// Bytes of flash.
    pub bytes: u32,
    /// Whether it is code (false: data tables).
    pub code: bool,
}

/// The ROM estimate, item by item: the controller's routines, the learner's routines, and the
/// data tables.
#[must_use]
pub fn rom_estimate() -> Vec<RomLine> {
    let mut lines: Vec<RomLine> = CONTROLLER_ROUTINES
        .iter()
        .map(|r| RomLine {
            name: r.name,
            bytes: r.bytes(),
            code: true,
        })
        .collect();
    lines.extend(LEARNER_ROUTINES.iter().map(|r| RomLine {
        name: r.name,
        bytes: r.bytes(),
        code: true,
    }));
    lines.push(RomLine {
        name: "exception vector table",
        bytes: VECTOR_TABLE_BYTES,
        code: false,
    });
    lines.push(RomLine {
        name: "du table (sensors::DU_TABLE)",
        bytes: DU_TABLE_BYTES,
        code: false,
    });
    lines.push(RomLine {
        name: "behaviour table (PWM duties, direction bits)",
        bytes: BEHAVIOUR_TABLE_BYTES,
        code: false,
    });
    lines
}

/// One frame of the deepest call chain.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// Which call.
    pub name: &'static str,
    /// Bytes it puts on the stack.
    pub bytes: u32,
}

/// The deepest call chain: main → save the record → write a page → send a byte → clock a bit
/// → delay, with the tick interrupt arriving at the bottom. A call pushes its 4-byte return
/// address (advanced mode); each routine saves the registers it uses (PUSH.L, 4 bytes each).
pub const DEEPEST_CALL_CHAIN: &[Frame] = &[
    Frame {
        name: "main → save_record (JSR, ER4–ER6 saved)",
        bytes: 4 + 12,
    },
    Frame {
        name: "save_record → i2c_page_write (JSR, ER4–ER5 saved)",
        bytes: 4 + 8,
    },
    Frame {
        name: "i2c_page_write → byte_out (JSR, ER4 saved)",
        bytes: 4 + 4,
    },
    Frame {
        name: "byte_out → clock_pulse (JSR)",
        bytes: 4,
    },
    Frame {
        name: "clock_pulse → delay (JSR)",
        bytes: 4,
    },
    Frame {
        name: "tick interrupt (PC and CCR, ER0 saved)",
        bytes: 4 + 4,
    },
];

/// The stack the controller needs: the sum of [`DEEPEST_CALL_CHAIN`] (the learner's chain,
/// main → a learner routine with ER4–ER6 saved, is shallower: 16 bytes).
#[must_use]
pub fn stack_bytes() -> u32 {
    DEEPEST_CALL_CHAIN.iter().map(|f| f.bytes).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimate_is_itemised_and_plausible() {
        let lines = rom_estimate();
        let code: u32 = lines.iter().filter(|l| l.code).map(|l| l.bytes).sum();
        let data: u32 = lines.iter().filter(|l| !l.code).map(|l| l.bytes).sum();
        assert_eq!(data, 244 + 256 + 32);
        // A few kilobytes of code at most: the H8/3052F has 512 KB of flash.
        assert!(code > 1000 && code < 4000, "{code}");
        assert_eq!(stack_bytes(), 16 + 12 + 8 + 4 + 4 + 8);
    }
}
