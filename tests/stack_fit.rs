//! `h8swarm fit` and the stack guard: the robot firmware's stack room (from the end of its
//! data and of the arrays it carves at boot to its initial SP) with what its lowest SP leaves
//! of it; and an image whose frame does not fit is a "does not fit" verdict that says where
//! and by how much, not an error.

use std::path::Path;

use robot_board::firmware::Firmware;
use robot_board::model::ControllerConfig;
use robot_board::profile::PhaseDef;
use swarm::fit::{FirmwareUnderTest, FitConfig, fit_weight_seed, measure};
use swarm::scenario::ControllerKind;

#[test]
fn the_robot_firmware_states_the_stack_room_it_leaves() {
    let r = measure(&FitConfig {
        controller: ControllerConfig::arena(fit_weight_seed(1)),
        steps: 60,
        seed: 1,
        kind: ControllerKind::Firmware,
        firmware: FirmwareUnderTest::robot().unwrap(),
        compare: false,
        strict_io: false,
    })
    .unwrap();
    let st = r.stack.clone().expect("measured on the core");
    assert!(r.fits, "{}", r.verdict);
    assert_eq!(st.overflow, None);
    assert_eq!(st.room_top, 0xFF_FF10);
    // The low end is past the network's arrays, which the firmware carved above .bss.
    let carved_end = r
        .ram
        .iter()
        .filter(|l| l.item.contains("carved at boot"))
        .map(|l| l.addr + l.bytes)
        .max()
        .unwrap();
    assert_eq!(st.room_low, carved_end);
    assert_eq!(
        st.left_bytes,
        i64::from(st.lowest_sp) - i64::from(st.room_low)
    );
    assert_eq!(st.room_top - st.lowest_sp, r.stack_high_water.unwrap());
    // What is left of the room is what the RAM total leaves of the 8 KB.
    assert_eq!(st.left_bytes, i64::from(8192 - r.ram_used));
}

#[test]
fn an_image_whose_frame_does_not_fit_does_not_fit_and_says_where() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("emu/tests/programs/stack");
    let fw = Firmware::load(&dir.join("stack_after.mot"), &dir.join("stack_after.sym")).unwrap();
    let r = measure(&FitConfig {
        // The settings of the firmware's compiled defaults (weight seed 1): an image without a
        // configuration block can be measured only under them.
        controller: ControllerConfig::arena(1),
        steps: 3,
        seed: 1,
        kind: ControllerKind::Firmware,
        firmware: FirmwareUnderTest {
            firmware: fw,
            phases: vec![PhaseDef::new("fill", &["fill"])],
        },
        compare: false,
        strict_io: false,
    })
    .unwrap();
    let st = r.stack.clone().unwrap();
    let text = st.overflow.clone().expect("the overflow");
    assert!(!r.fits);
    assert_eq!(r.tightest, "stack");
    assert!(r.tightest_margin_percent < 0.0);
    assert!(
        r.verdict
            .starts_with("DOES NOT FIT: the stack leaves its room by")
    );
    assert!(text.contains("in `fill`"), "{text}");
    assert_eq!(st.overflow_bytes, Some(16), "{text}");
}

fn h8swarm(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

#[test]
fn emu_stops_at_the_overflow_with_one_line_or_warns_when_asked() {
    let image = "emu/tests/programs/stack/stack_deep.mot";
    let out = h8swarm(&["emu", image]);
    assert_eq!(out.status.code(), Some(125));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("stack overflow at PC H'") && err.contains("in `descend`"),
        "{err}"
    );
    assert!(
        err.contains("with SP H'") || err.contains("moves SP from H'"),
        "{err}"
    );
    let out = h8swarm(&[
        "emu",
        image,
        "--stack-guard",
        "warn",
        "--max-states",
        "5000000",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.lines()
            .any(|l| l.starts_with("warning: image") && l.contains("in `descend`")),
        "{err}"
    );
    // The close one is not stopped.
    let out = h8swarm(&["emu", "emu/tests/programs/stack/stack_close.mot"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(out.stderr.is_empty());
}

#[test]
fn run_stops_a_firmware_robot_whose_stack_overflows_or_lists_it_with_warn() {
    let dir = std::env::temp_dir().join(format!("h8swarm-stack-{}", std::process::id()));
    let out_dir = dir.to_str().unwrap();
    let image = "emu/tests/programs/stack/stack_deep.mot";
    // The test images have no configuration block, so the controls cannot reach them: the
    // learning condition alone.
    let base = [
        "run",
        "scenarios/arena-learning-only.toml",
        "--steps",
        "3",
        "--repeats",
        "1",
        "--out",
        out_dir,
    ];
    let mut args = base.to_vec();
    args.extend(["--firmware", image]);
    let out = h8swarm(&args);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    // A warning that the image runs with its own settings, then one error line.
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error: ")).collect();
    assert_eq!(errors.len(), 1, "{err}");
    assert!(
        errors[0].contains("robot 0") && errors[0].contains("stack overflow at PC"),
        "{err}"
    );
    args.extend(["--stack-guard", "warn", "--keep-going"]);
    let out = h8swarm(&args);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.lines()
            .any(|l| l.starts_with("STACK robot 0 in learning repeat 0: stack overflow")),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
