//! The GDB stub against a client that breaks the remote protocol's rules, in raw bytes over
//! loopback: over-long and endless packets, bad checksums, malformed packets, a bare
//! `qSupported`, a `-` asking for the last reply again. Each gets the protocol's answer (`-`
//! for a bad checksum, an `E` reply for a packet the stub cannot take) and the session goes
//! on: the same stub answers a well-formed packet afterwards.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::thread::JoinHandle;
use std::time::Duration;

use h8_3052f::gdb::{GdbListener, MAX_PACKET_BYTES};
use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::pins::NullBoard;
use h8_3052f::run::{Outcome, Probes, RunOptions, RunReport, run_mcu_probed};
use h8300h::cpu::Cpu;
use robot_board::firmware::Firmware;

/// The firmware under a stub on a free loopback port, and a raw connection to it.
fn session() -> (TcpStream, JoinHandle<RunReport>) {
    let listener = GdbListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr();
    let run = std::thread::spawn(move || {
        let mut debugger = listener.accept().unwrap();
        let fw = Firmware::robot().unwrap();
        let mut mcu = Mcu::new(McuConfig::default(), NullBoard).unwrap();
        let mut cpu = Cpu::new();
        fw.install(&mut mcu, &mut cpu, None).unwrap();
        run_mcu_probed(
            &mut cpu,
            &mut mcu,
            &RunOptions {
                max_states: Some(2_000_000),
                ..RunOptions::default()
            },
            &mut std::io::sink(),
            Probes {
                debugger: Some(&mut debugger),
                ..Probes::default()
            },
        )
        .unwrap()
    });
    let s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    (s, run)
}

fn packet(body: &[u8]) -> Vec<u8> {
    let sum = body.iter().fold(0u8, |a, b| a.wrapping_add(*b));
    let mut p = vec![b'$'];
    p.extend_from_slice(body);
    p.extend_from_slice(format!("#{sum:02x}").as_bytes());
    p
}

fn byte(s: &mut TcpStream) -> u8 {
    let mut b = [0u8; 1];
    s.read_exact(&mut b).expect("the stub answers");
    b[0]
}

/// The next packet's body (checksum checked), acknowledged.
fn reply(s: &mut TcpStream) -> String {
    while byte(s) != b'$' {}
    let mut body = Vec::new();
    loop {
        match byte(s) {
            b'#' => break,
            b => body.push(b),
        }
    }
    let sum = [byte(s), byte(s)];
    let want = u8::from_str_radix(std::str::from_utf8(&sum).unwrap(), 16).unwrap();
    assert_eq!(body.iter().fold(0u8, |a, b| a.wrapping_add(*b)), want);
    s.write_all(b"+").unwrap();
    expand(&body)
}

/// A reply with its run-length encoding (`c*n`: n − 29 more of c) expanded.
fn expand(raw: &[u8]) -> String {
    let mut out: Vec<u8> = Vec::new();
    let mut i = 0;
    while i < raw.len() {
        if raw[i] == b'*' && i + 1 < raw.len() {
            let last = *out.last().expect("a run follows a character");
            out.extend(std::iter::repeat_n(last, usize::from(raw[i + 1]) - 29));
            i += 2;
        } else {
            out.push(raw[i]);
            i += 1;
        }
    }
    String::from_utf8(out).unwrap()
}

/// Sends raw bytes; returns the acknowledgement byte and, after a `+`, the reply.
fn exchange(s: &mut TcpStream, raw: &[u8]) -> (u8, Option<String>) {
    s.write_all(raw).unwrap();
    let ack = byte(s);
    (ack, (ack == b'+').then(|| reply(s)))
}

fn ask(s: &mut TcpStream, body: &str) -> String {
    let (ack, r) = exchange(s, &packet(body.as_bytes()));
    assert_eq!(ack, b'+', "{body}");
    r.unwrap()
}

fn end(mut s: TcpStream, run: JoinHandle<RunReport>) {
    assert_eq!(ask(&mut s, "D"), "OK");
    let report = run.join().unwrap();
    assert_eq!(report.outcome, Outcome::MaxStates);
}

#[test]
fn a_bare_qsupported_gets_the_stubs_features() {
    let (mut s, run) = session();
    let features = ask(&mut s, "qSupported");
    assert!(
        features.contains(&format!("PacketSize={MAX_PACKET_BYTES:x}")),
        "{features}"
    );
    assert!(ask(&mut s, "?").starts_with('S') || ask(&mut s, "?").starts_with('T'));
    end(s, run);
}

#[test]
fn a_bad_checksum_is_answered_with_a_nak_and_the_session_goes_on() {
    let (mut s, run) = session();
    ask(&mut s, "qSupported:swbreak+;hwbreak+");
    let (ack, _) = exchange(&mut s, b"$g#00");
    assert_eq!(ack, b'-');
    let (ack, _) = exchange(&mut s, b"$g#zz");
    assert_eq!(ack, b'-');
    let regs = ask(&mut s, "g");
    assert_eq!(regs.len(), 13 * 8, "{regs}");
    end(s, run);
}

#[test]
fn malformed_packets_get_an_error_reply_and_the_session_goes_on() {
    let (mut s, run) = session();
    ask(&mut s, "qSupported:swbreak+");
    for bad in [
        "mzz,4",
        "m100",
        "Mffdf00,2:zz",
        "Z0,zz,2",
        "qSupported:a;;b",
        "Gzz",
        "G00",
    ] {
        let r = ask(&mut s, bad);
        assert!(r.starts_with('E'), "{bad}: {r}");
    }
    // Junk between packets is skipped.
    s.write_all(b"junk\r\n").unwrap();
    assert_eq!(ask(&mut s, "m0,2").len(), 4);
    end(s, run);
}

#[test]
fn over_long_and_endless_packets_are_bounded_and_answered() {
    let (mut s, run) = session();
    ask(&mut s, "qSupported:swbreak+");
    // Longer than the stub takes, with a right checksum: an error reply (E2BIG).
    let long = vec![b'q'; MAX_PACKET_BYTES * 2];
    let (ack, r) = exchange(&mut s, &packet(&long));
    assert_eq!((ack, r.as_deref()), (b'+', Some("E07")));
    // 4 MB of a packet that never ends, then a packet: the endless one is dropped unread
    // (its bytes are only counted), the next one answered.
    let mut endless = vec![b'$'];
    endless.extend(std::iter::repeat_n(b'm', 4 << 20));
    let writer = {
        let mut w = s.try_clone().unwrap();
        std::thread::spawn(move || w.write_all(&endless).unwrap())
    };
    writer.join().unwrap();
    assert_eq!(ask(&mut s, "m0,2").len(), 4);
    end(s, run);
}

#[test]
fn a_nak_gets_the_last_reply_again() {
    let (mut s, run) = session();
    ask(&mut s, "qSupported:swbreak+");
    s.write_all(&packet(b"m0,4")).unwrap();
    assert_eq!(byte(&mut s), b'+');
    let first = {
        // Read the reply without acknowledging it, then ask for it again.
        while byte(&mut s) != b'$' {}
        let mut body = Vec::new();
        loop {
            match byte(&mut s) {
                b'#' => break,
                b => body.push(b),
            }
        }
        let _ = (byte(&mut s), byte(&mut s));
        expand(&body)
    };
    s.write_all(b"-").unwrap();
    assert_eq!(reply(&mut s), first);
    end(s, run);
}
