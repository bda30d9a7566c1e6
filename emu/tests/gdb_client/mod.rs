//! A small GDB Remote Serial Protocol client for the tests, written here from the protocol's
//! description (GDB manual, appendix "Remote Protocol"): packets `$data#checksum`, `+` acks,
//! run-length encoding, hex-encoded memory and registers, `O` console packets.
#![allow(dead_code)]

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

/// A connection to a stub.
pub struct Client {
    s: TcpStream,
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Bytes from hex text.
pub fn unhex(text: &str) -> Vec<u8> {
    (0..text.len() / 2)
        .map(|i| u8::from_str_radix(&text[2 * i..2 * i + 2], 16).expect("hex"))
        .collect()
}

impl Client {
    /// Connects, retrying for up to 20 s while the stub comes up.
    pub fn connect(addr: SocketAddr) -> Client {
        let start = Instant::now();
        loop {
            match TcpStream::connect(addr) {
                Ok(s) => {
                    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
                    s.set_nodelay(true).unwrap();
                    return Client { s };
                }
                Err(e) if start.elapsed() < Duration::from_secs(20) => {
                    let _ = e;
                    std::thread::sleep(Duration::from_millis(20));
                }
                Err(e) => panic!("cannot connect to {addr}: {e}"),
            }
        }
    }

    fn byte(&mut self) -> u8 {
        let mut b = [0u8; 1];
        self.s.read_exact(&mut b).expect("the stub answers");
        b[0]
    }

    /// Sends a packet and waits for its acknowledgement.
    pub fn send(&mut self, payload: &str) {
        let sum = payload.bytes().fold(0u8, |a, b| a.wrapping_add(b));
        write!(self.s, "${payload}#{sum:02x}").unwrap();
        match self.byte() {
            b'+' => {}
            b'-' => panic!("the stub refused packet {payload}"),
            other => panic!("expected an ack for {payload}, got {:?}", other as char),
        }
    }

    /// Receives one packet (checksum checked, run-length encoding expanded) and acks it.
    pub fn recv(&mut self) -> String {
        while self.byte() != b'$' {}
        let mut raw = Vec::new();
        loop {
            let b = self.byte();
            if b == b'#' {
                break;
            }
            raw.push(b);
        }
        let sum = [self.byte(), self.byte()];
        let want = u8::from_str_radix(std::str::from_utf8(&sum).unwrap(), 16).unwrap();
        let got = raw.iter().fold(0u8, |a, b| a.wrapping_add(*b));
        assert_eq!(got, want, "checksum of {:?}", String::from_utf8_lossy(&raw));
        self.s.write_all(b"+").unwrap();
        let mut out: Vec<u8> = Vec::new();
        let mut i = 0;
        while i < raw.len() {
            if raw[i] == b'*' && i + 1 < raw.len() {
                let n = usize::from(raw[i + 1]) - 29;
                let last = *out.last().expect("a run follows a character");
                out.extend(std::iter::repeat_n(last, n));
                i += 2;
            } else {
                out.push(raw[i]);
                i += 1;
            }
        }
        String::from_utf8(out).expect("text")
    }

    /// Sends a packet and returns the reply.
    pub fn ask(&mut self, payload: &str) -> String {
        self.send(payload);
        self.recv()
    }

    /// The usual opening: features, then the stop reason.
    pub fn handshake(&mut self) -> String {
        let features = self.ask("qSupported:swbreak+;hwbreak+;xmlRegisters=h8300");
        assert!(features.contains("PacketSize"), "{features}");
        self.ask("?")
    }

    /// The registers (`g`): big-endian 32-bit words.
    pub fn registers(&mut self) -> Vec<u32> {
        let r = self.ask("g");
        assert!(!r.starts_with('E'), "g: {r}");
        unhex(&r)
            .chunks(4)
            .map(|c| u32::from_be_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    /// Reads memory (`m`); `None` on an error reply.
    pub fn read(&mut self, addr: u32, len: usize) -> Option<Vec<u8>> {
        let r = self.ask(&format!("m{addr:x},{len:x}"));
        if r.starts_with('E') {
            None
        } else {
            Some(unhex(&r))
        }
    }

    /// Writes memory (`M`): the reply (`OK` or an error).
    pub fn write(&mut self, addr: u32, bytes: &[u8]) -> String {
        self.ask(&format!("M{addr:x},{:x}:{}", bytes.len(), hex(bytes)))
    }

    /// A monitor command (`qRcmd`): its console output.
    pub fn monitor(&mut self, cmd: &str) -> String {
        self.send(&format!("qRcmd,{}", hex(cmd.as_bytes())));
        let mut text = String::new();
        loop {
            let r = self.recv();
            if r == "OK" {
                return text;
            }
            let Some(o) = r.strip_prefix('O') else {
                panic!("monitor {cmd}: {r}");
            };
            text.push_str(&String::from_utf8_lossy(&unhex(o)));
        }
    }
}
