//! Motorola S-record images (`.mot`, as flashed onto real H8/3052F boards; docs/design.md §7).
//!
//! Record types: S0 header, S1/S2/S3 data with 16/24/32-bit addresses, S5/S6 record counts
//! (checked against the number of data records), S7/S8/S9 start address with 32/24/16 bits.
//! Every record's byte count and checksum (ones' complement of the low byte of the sum of
//! count, address and data bytes) are verified. Blank lines and trailing whitespace (CR LF
//! line ends) are accepted; anything else that is not a well-formed record is an error naming
//! the line. The parser never panics on any input.

/// What is wrong with an S-record file.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("S-record line {line}: {problem}")]
pub struct SrecError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong there.
    pub problem: SrecProblem,
}

/// The kinds of malformed record.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SrecProblem {
    /// The line does not start with `S`.
    #[error("does not start with 'S' (every record is S<type><count><address><data><checksum>)")]
    NoS,
    /// The record type is not 0–3 or 5–9.
    #[error("unknown record type {0:?} (valid: S0, S1, S2, S3, S5, S6, S7, S8, S9)")]
    BadType(char),
    /// A character that is not a hexadecimal digit.
    #[error("character {ch:?} at column {column} is not a hexadecimal digit")]
    NotHex {
        /// The character.
        ch: char,
        /// 1-based column.
        column: usize,
    },
    /// An odd number of hexadecimal digits after the type.
    #[error("odd number of hexadecimal digits ({0}) after the record type")]
    OddDigits(usize),
    /// The record is shorter than its type needs.
    #[error("truncated record: {have} bytes after the type, needs at least {need}")]
    Truncated {
        /// Bytes present (count byte included).
        have: usize,
        /// Bytes needed.
        need: usize,
    },
    /// The count byte disagrees with the record length.
    #[error("byte count says {count} but {actual} bytes follow it")]
    CountMismatch {
        /// The count field.
        count: usize,
        /// Bytes actually after the count field.
        actual: usize,
    },
    /// The checksum is wrong.
    #[error("checksum is {found:02X}, the record's bytes give {expected:02X}")]
    Checksum {
        /// Checksum in the record.
        found: u8,
        /// Checksum computed from the record.
        expected: u8,
    },
    /// A data record that ends past the 32-bit address space.
    #[error("data at {address:#X} + {len} bytes runs past the end of the address space")]
    AddressOverflow {
        /// Start address.
        address: u32,
        /// Data bytes.
        len: usize,
    },
    /// An S5/S6 count that disagrees with the data records before it.
    #[error("record count says {count} data records, the file has {actual} before it")]
    RecordCount {
        /// The count in the S5/S6 record.
        count: u32,
        /// Data records seen.
        actual: u32,
    },
    /// Nothing after the last termination record may follow it except blank lines.
    #[error("record after the termination record (S7/S8/S9) on line {0}")]
    AfterEnd(usize),
}

/// One run of data bytes at consecutive addresses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Chunk {
    /// Address of the first byte.
    pub address: u32,
    /// The bytes.
    pub data: Vec<u8>,
}

/// A parsed S-record file.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SrecImage {
    /// The S0 header's data bytes (often a module name), if any.
    pub header: Option<Vec<u8>>,
    /// Data records in file order.
    pub chunks: Vec<Chunk>,
    /// The start address of the S7/S8/S9 record, if any. (The H8/300H starts at the reset
    /// vector regardless.)
    pub start: Option<u32>,
}

impl SrecImage {
    /// Total data bytes.
    #[must_use]
    pub fn data_len(&self) -> usize {
        self.chunks.iter().map(|c| c.data.len()).sum()
    }
}

fn hex_val(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

/// Parses an S-record file.
///
/// ```
/// // Two bytes at H'000100 (an S1 record) and the end record (S9).
/// let image = h8300h::srec::parse(b"S1050100F82AD7\nS9030000FC\n").unwrap();
/// assert_eq!(image.chunks[0].address, 0x100);
/// assert_eq!(image.chunks[0].data, [0xF8, 0x2A]);
/// assert!(h8300h::srec::parse(b"S1050100F82AD6\n").is_err()); // bad checksum
/// ```
///
/// # Errors
/// [`SrecError`] naming the first bad line and what is wrong with it.
pub fn parse(text: &[u8]) -> Result<SrecImage, SrecError> {
    let mut image = SrecImage::default();
    let mut data_records: u32 = 0;
    let mut end_line: Option<usize> = None;
    for (i, raw) in text.split(|&b| b == b'\n').enumerate() {
        let line_no = i + 1;
        let err = |problem| SrecError {
            line: line_no,
            problem,
        };
        let line = raw.trim_ascii();
        if line.is_empty() {
            continue;
        }
        if let Some(end) = end_line {
            return Err(err(SrecProblem::AfterEnd(end)));
        }
        if line[0] != b'S' && line[0] != b's' {
            return Err(err(SrecProblem::NoS));
        }
        let Some(&tch) = line.get(1) else {
            return Err(err(SrecProblem::Truncated { have: 0, need: 3 }));
        };
        let rtype = match tch {
            b'0'..=b'3' | b'5'..=b'9' => tch - b'0',
            _ => return Err(err(SrecProblem::BadType(char::from(tch)))),
        };
        let digits = &line[2..];
        if let Some(pos) = digits.iter().position(|&c| hex_val(c).is_none()) {
            return Err(err(SrecProblem::NotHex {
                ch: char::from(digits[pos]),
                column: pos + 3,
            }));
        }
        if digits.len() % 2 != 0 {
            return Err(err(SrecProblem::OddDigits(digits.len())));
        }
        let bytes: Vec<u8> = digits
            .chunks(2)
            .map(|p| (hex_val(p[0]).unwrap_or(0) << 4) | hex_val(p[1]).unwrap_or(0))
            .collect();
        let addr_len = match rtype {
            0 | 1 | 5 | 9 => 2,
            2 | 6 | 8 => 3,
            _ => 4,
        };
        // count + address + checksum
        let need = 1 + addr_len + 1;
        if bytes.len() < need {
            return Err(err(SrecProblem::Truncated {
                have: bytes.len(),
                need,
            }));
        }
        let count = usize::from(bytes[0]);
        if count != bytes.len() - 1 {
            return Err(err(SrecProblem::CountMismatch {
                count,
                actual: bytes.len() - 1,
            }));
        }
        let (body, check) = bytes.split_at(bytes.len() - 1);
        let sum = body.iter().fold(0u8, |s, &b| s.wrapping_add(b));
        let expected = !sum;
        if check[0] != expected {
            return Err(err(SrecProblem::Checksum {
                found: check[0],
                expected,
            }));
        }
        let address = body[1..=addr_len]
            .iter()
            .fold(0u32, |a, &b| (a << 8) | u32::from(b));
        let data = &body[1 + addr_len..];
        match rtype {
            0 => image.header = Some(data.to_vec()),
            1..=3 => {
                if u64::from(address) + data.len() as u64 > 1 << 32 {
                    return Err(err(SrecProblem::AddressOverflow {
                        address,
                        len: data.len(),
                    }));
                }
                data_records = data_records.saturating_add(1);
                // Merge with the previous chunk when contiguous (the usual case).
                match image.chunks.last_mut() {
                    Some(c) if u64::from(c.address) + c.data.len() as u64 == u64::from(address) => {
                        c.data.extend_from_slice(data);
                    }
                    _ => image.chunks.push(Chunk {
                        address,
                        data: data.to_vec(),
                    }),
                }
            }
            5 | 6 => {
                if address != data_records {
                    return Err(err(SrecProblem::RecordCount {
                        count: address,
                        actual: data_records,
                    }));
                }
            }
            _ => {
                image.start = Some(address);
                end_line = Some(line_no);
            }
        }
    }
    Ok(image)
}

/// Writes an image as S-records (S0 header, S3 data records of up to `bytes_per_record` bytes,
/// S7 start address). Used by tests and benchmarks to build images.
#[must_use]
pub fn write_s3(image: &SrecImage, bytes_per_record: usize) -> String {
    fn record(out: &mut String, rtype: u8, addr: &[u8], data: &[u8]) {
        let count = (addr.len() + data.len() + 1) as u8;
        let mut sum = count;
        out.push('S');
        out.push(char::from(b'0' + rtype));
        out.push_str(&format!("{count:02X}"));
        for &b in addr.iter().chain(data) {
            sum = sum.wrapping_add(b);
            out.push_str(&format!("{b:02X}"));
        }
        out.push_str(&format!("{:02X}\n", !sum));
    }
    let per = bytes_per_record.clamp(1, 250);
    let mut out = String::new();
    record(
        &mut out,
        0,
        &[0, 0],
        image.header.as_deref().unwrap_or_default(),
    );
    for c in &image.chunks {
        for (k, part) in c.data.chunks(per).enumerate() {
            let a = c.address.wrapping_add((k * per) as u32);
            record(&mut out, 3, &a.to_be_bytes(), part);
        }
    }
    record(&mut out, 7, &image.start.unwrap_or(0).to_be_bytes(), &[]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_a_small_file() {
        // S1 record from the classic Motorola example, with header and S9.
        let text = b"S00600004844521B\nS1130000285F245F2212226A000424290008237C2A\nS5030001FB\nS9030000FC\n";
        let img = parse(text).unwrap();
        assert_eq!(img.header.as_deref(), Some(&b"HDR"[..]));
        assert_eq!(img.chunks.len(), 1);
        assert_eq!(img.chunks[0].address, 0);
        assert_eq!(img.chunks[0].data.len(), 16);
        assert_eq!(img.start, Some(0));
    }

    #[test]
    fn round_trips_through_the_writer() {
        let img = SrecImage {
            header: Some(b"t".to_vec()),
            chunks: vec![Chunk {
                address: 0x100,
                data: (0..=255).collect(),
            }],
            start: Some(0x100),
        };
        let text = write_s3(&img, 32);
        assert_eq!(parse(text.as_bytes()).unwrap(), img);
    }

    #[test]
    fn bad_checksum_names_the_line() {
        let text = b"S00600004844521B\nS1130000285F245F2212226A000424290008237C2B\n";
        let e = parse(text).unwrap_err();
        assert_eq!(e.line, 2);
        assert!(matches!(e.problem, SrecProblem::Checksum { .. }));
        assert!(e.to_string().contains("line 2"));
    }

    #[test]
    fn truncated_record_is_an_error() {
        let e = parse(b"S1130000285F245F22\n").unwrap_err();
        assert!(matches!(e.problem, SrecProblem::CountMismatch { .. }));
        let e = parse(b"S1\n").unwrap_err();
        assert!(matches!(e.problem, SrecProblem::Truncated { .. }));
        let e = parse(b"S4030000FC\n").unwrap_err();
        assert!(matches!(e.problem, SrecProblem::BadType('4')));
        let e = parse(b"X1030000FC\n").unwrap_err();
        assert!(matches!(e.problem, SrecProblem::NoS));
        let e = parse(b"S10300G0FC\n").unwrap_err();
        assert!(matches!(e.problem, SrecProblem::NotHex { ch: 'G', .. }));
    }

    #[test]
    fn wrong_record_count_is_an_error() {
        let e = parse(b"S5030002FA\n").unwrap_err();
        assert!(matches!(e.problem, SrecProblem::RecordCount { .. }));
    }
}
