//! CRC-16/CCITT-FALSE, as the H8 firmware computes it bit by bit (no table: 512 bytes of ROM
//! saved, and a record is only a few hundred bytes). The host feeds a byte through a table
//! built from that bitwise routine at compile time: the eight steps depend only on the top
//! byte of the register after the byte is XORed in, so a byte costs one look-up, and the
//! table also holds how many of the eight steps XOR the polynomial (the firmware's state
//! count). A test checks the table against the bitwise routine for every register and byte.
//!
//! Parameters (the Rocksoft/Williams model, as catalogued by Greg Cook's CRC RevEng list):
//! width 16, poly 0x1021, init 0xFFFF, refin false, refout false, xorout 0x0000,
//! check 0x29B1 (the CRC of the ASCII bytes "123456789").

/// Generator polynomial x^16 + x^12 + x^5 + 1, MSB-first form.
pub const CRC16_POLY: u16 = 0x1021;
/// Initial register value of CRC-16/CCITT-FALSE.
pub const CRC16_INIT: u16 = 0xFFFF;
/// CRC-16/CCITT-FALSE of the ASCII string "123456789" (the catalogue's check value).
pub const CRC16_CHECK: u16 = 0x29B1;

/// Feeds one byte into the CRC register: the byte goes into the high half, then eight
/// shift-and-conditionally-XOR steps, MSB first.
#[must_use]
pub const fn crc16_update(crc: u16, byte: u8) -> u16 {
    crc16_update_counting(crc, byte).0
}

/// [`crc16_update`], also counting how many of its eight steps XOR the polynomial: what the
/// bitwise routine's conditional XOR costs on a CPU that runs it (the firmware's state count).
/// One look-up in a 256-entry table built at compile time.
#[must_use]
pub const fn crc16_update_counting(crc: u16, byte: u8) -> (u16, u32) {
    let (xor, xors) = BYTE_STEPS[((crc >> 8) as u8 ^ byte) as usize];
    ((crc << 8) ^ xor, xors as u32)
}

/// The eight steps of a byte, by the register's top byte after the byte is XORed in: what they
/// XOR into the register shifted left by eight, and how many of them XOR the polynomial. The
/// low byte only shifts out of the way, so the steps depend on the top byte alone.
const BYTE_STEPS: [(u16, u8); 256] = {
    let mut t = [(0u16, 0u8); 256];
    let mut top = 0;
    while top < 256 {
        let (c, xors) = crc16_update_bitwise((top as u16) << 8, 0);
        t[top] = (c, xors as u8);
        top += 1;
    }
    t
};

/// The firmware's routine: the byte into the register's high half, then eight
/// shift-and-conditionally-XOR steps, MSB first, counting the XORs.
const fn crc16_update_bitwise(crc: u16, byte: u8) -> (u16, u32) {
    let mut c = crc ^ ((byte as u16) << 8);
    let mut xors = 0;
    let mut i = 0;
    while i < 8 {
        c = if c & 0x8000 != 0 {
            xors += 1;
            (c << 1) ^ CRC16_POLY
        } else {
            c << 1
        };
        i += 1;
    }
    (c, xors)
}

/// CRC-16/CCITT-FALSE of `data`.
#[must_use]
pub fn crc16_ccitt_false(data: &[u8]) -> u16 {
    data.iter().fold(CRC16_INIT, |c, &b| crc16_update(c, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A bit-serial LFSR, one message bit per step (the hardware form), independent of the
    /// byte-at-a-time loop above.
    fn crc_bit_serial(data: &[u8]) -> u16 {
        let mut reg: u16 = CRC16_INIT;
        for &byte in data {
            for i in (0..8).rev() {
                let feedback = ((reg >> 15) as u8 ^ (byte >> i)) & 1;
                reg <<= 1;
                if feedback == 1 {
                    reg ^= CRC16_POLY;
                }
            }
        }
        reg
    }

    #[test]
    fn check_value_of_123456789() {
        assert_eq!(crc16_ccitt_false(b"123456789"), CRC16_CHECK);
        assert_eq!(CRC16_CHECK, 0x29B1);
    }

    #[test]
    fn empty_message_is_the_init_value() {
        assert_eq!(crc16_ccitt_false(&[]), 0xFFFF);
    }

    #[test]
    fn xors_are_the_steps_with_the_top_bit_set() {
        // 0x80 into 0: step 1 XORs (0x8000), giving 0x1021; three shifts make 0x8108, so
        // step 5 XORs again; the last three shift 0x1231 to 0x9188 without one.
        assert_eq!(crc16_update_counting(0, 0x80), (crc16_update(0, 0x80), 2));
        assert_eq!(crc16_update_counting(0, 0), (0, 0));
    }

    #[test]
    fn the_table_is_the_bitwise_routine_for_every_register_and_byte() {
        for crc in 0..=u16::MAX {
            for byte in 0..=u8::MAX {
                assert_eq!(
                    crc16_update_counting(crc, byte),
                    crc16_update_bitwise(crc, byte),
                    "{crc:#06x} {byte:#04x}"
                );
            }
        }
    }

    #[test]
    fn bit_serial_agrees_on_the_check_string() {
        assert_eq!(crc_bit_serial(b"123456789"), 0x29B1);
    }

    proptest! {
        #[test]
        fn bytewise_equals_bit_serial(data in proptest::collection::vec(any::<u8>(), 0..80)) {
            prop_assert_eq!(crc16_ccitt_false(&data), crc_bit_serial(&data));
        }

        #[test]
        fn any_single_bit_flip_is_detected(
            data in proptest::collection::vec(any::<u8>(), 1..200),
            pos in any::<usize>(),
            bit in 0u8..8,
        ) {
            let mut d = data.clone();
            let i = pos % d.len();
            d[i] ^= 1 << bit;
            prop_assert_ne!(crc16_ccitt_false(&d), crc16_ccitt_false(&data));
        }
    }
}
