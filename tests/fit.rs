//! `h8swarm fit` measured on the firmware, with the model beside it: the model's figures per
//! phase against the firmware's over a grid of networks, and the command's
//! options for a user's image.

use std::process::Command;

use nn_q15::InputLayout;
use robot_board::model::ControllerConfig;
use swarm::fit::{FirmwareUnderTest, FitConfig, fit_weight_seed, measure};
use swarm::scenario::ControllerKind;

fn config(behaviours: usize, layout: InputLayout, corridor: bool) -> FitConfig {
    let seed = 3;
    let mut controller = if corridor {
        ControllerConfig::corridor(fit_weight_seed(seed))
    } else {
        ControllerConfig::arena(fit_weight_seed(seed))
    };
    controller.behaviours = behaviours;
    controller.layout = layout;
    controller.save_every_steps = 10;
    FitConfig {
        controller,
        steps: 60,
        seed,
        kind: ControllerKind::Firmware,
        firmware: FirmwareUnderTest::robot().unwrap(),
        compare: true,
        strict_io: false,
    }
}

/// Every phase of the model's step within ±5 % of the firmware's mean and its worst step within
/// ±10 %, for M 2–4, history 0, 1 and 8, the bias, and spare inputs up to N = 256.
#[test]
fn the_model_controller_follows_the_firmware_phase_by_phase() {
    let mut checked = 0;
    for m in [2usize, 3, 4] {
        for (history, bias, spare) in [(0, false, 0), (1, false, 0), (8, true, 0), (1, false, 40)] {
            let layout = InputLayout::new(history, bias).unwrap().with_spare(spare);
            let r = measure(&config(m, layout, m == 2)).unwrap();
            for p in &r.phases {
                let Some(o) = p.other else { continue };
                if p.states.mean == 0.0 && o.mean == 0.0 {
                    continue;
                }
                let label = format!("{}x{m} H{history} bias {bias}: {}", r.n_in, p.phase);
                let ratio = p.ratio.unwrap_or(f64::NAN);
                assert!(
                    (ratio - 1.0).abs() <= 0.05,
                    "{label}: firmware {} model {}",
                    p.states.mean,
                    o.mean
                );
                assert!(
                    (p.states.max as f64 / o.max as f64 - 1.0).abs() <= 0.10,
                    "{label}: worst firmware {} model {}",
                    p.states.max,
                    o.max
                );
                checked += 1;
            }
        }
    }
    // The largest network: 256 inputs x 4.
    let own = InputLayout::DEFAULT.n_inputs(4);
    let r = measure(&config(
        4,
        InputLayout::DEFAULT.with_spare((256 - own) as u16),
        false,
    ))
    .unwrap();
    assert_eq!(r.n_in, 256);
    for p in &r.phases {
        if let Some(ratio) = p.ratio {
            assert!((ratio - 1.0).abs() <= 0.05, "256x4 {}: {ratio}", p.phase);
        }
    }
    assert!(checked > 80, "{checked}");
}

#[test]
fn the_firmware_fits_with_ram_rom_and_stack_measured() {
    let r = measure(&config(4, InputLayout::DEFAULT, false)).unwrap();
    assert!(r.fits, "{}", r.verdict);
    let image = FirmwareUnderTest::robot().unwrap().firmware.rom_bytes() as u32;
    assert_eq!(r.rom_used, image);
    let stack = r.stack_high_water.unwrap();
    // The model places the firmware's measured stack in its RAM map.
    assert_eq!(
        stack,
        robot_board::model::MODEL_STACK_BYTES,
        "the firmware's stack changed"
    );
    // The network's arrays as the firmware carved them: 2NM + 2N + 4M + 2M + N (even).
    let carved: u32 = r
        .ram
        .iter()
        .filter(|l| l.item.contains("[carved at boot]"))
        .map(|l| l.bytes)
        .sum();
    assert_eq!(carved, 2 * 13 * 4 + 2 * 13 + 4 * 4 + 2 * 4 + 14);
    assert_eq!(r.ram_used, r.ram.iter().map(|l| l.bytes).sum::<u32>());
    // Every step period has its ticks: 45 of them, 111 states each.
    let ticks = r
        .phases
        .iter()
        .find(|p| p.phase == "tick interrupts")
        .unwrap();
    assert_eq!(ticks.states.max, 45 * 111);
}

fn h8swarm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn a_users_image_with_its_symbols_and_phases() {
    let dir = std::env::temp_dir().join(format!("h8swarm-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let image = dir.join("mine.mot");
    std::fs::copy("firmware/robot.mot", &image).unwrap();
    std::fs::copy("firmware/robot.sym", dir.join("mine.sym")).unwrap();
    let img = image.to_str().unwrap();
    let out = h8swarm(&[
        "fit",
        "--setting",
        "arena",
        "--steps",
        "30",
        "--firmware",
        img,
        "--phase",
        "learning=learner_step,learner_update,learner_forward",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let report = &v["reports"][0][1];
    assert_eq!(report["source"], img);
    let phases = report["phases"].as_array().unwrap();
    assert_eq!(phases[0]["phase"], "learning");
    assert!(phases[0]["states"]["mean"].as_f64().unwrap() > 5_000.0);
    assert!(report.get("compared_with").is_none());

    // A phase naming a function the image lacks, a missing symbol file: errors, status 2.
    let out = h8swarm(&["fit", "--firmware", img, "--phase", "x=no_such_function"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no function `no_such_function`"), "{err}");
    std::fs::remove_file(dir.join("mine.sym")).unwrap();
    let out = h8swarm(&["fit", "--firmware", img]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("mine.sym"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_image_without_a_configuration_block_takes_no_what_ifs() {
    // arith.mot (a differential test program) with a symbol table that has its _start but no
    // config_block.
    let sym = std::env::temp_dir().join(format!("h8swarm-arith-{}.sym", std::process::id()));
    std::fs::write(&sym, "000000f4 T _start\n").unwrap();
    let out = h8swarm(&[
        "fit",
        "--firmware",
        "emu/tests/programs/arith.mot",
        "--symbols",
        sym.to_str().unwrap(),
        "--outputs",
        "2",
    ]);
    let _ = std::fs::remove_file(&sym);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("configuration block"), "{err}");
}

#[test]
fn the_default_fit_is_the_firmware_with_the_model_beside() {
    let out = h8swarm(&["fit", "--setting", "arena", "--steps", "40"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("firmware/robot.mot on the H8/300H core; beside it: model"),
        "{text}"
    );
    assert!(
        text.contains("model mean") && text.contains("ratio"),
        "{text}"
    );
    assert!(text.contains("verdict: FITS"), "{text}");
    let out = h8swarm(&[
        "fit",
        "--setting",
        "arena",
        "--steps",
        "40",
        "--controller",
        "model",
    ]);
    assert!(out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stdout)
            .contains("the Rust model of the controller; beside it: firmware/robot.mot")
    );
}

/// `fit` names the network it measures: the paper's (η = 0.001 in the arena), and says that
/// `run arena` runs another one, the run's network (η = 0.03), which a run's fit.json measures;
/// the corridor's run uses the paper's network.
#[test]
fn fit_says_which_network_it_measures() {
    let out = h8swarm(&["fit", "--steps", "20"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let headings: Vec<&str> = text.lines().filter(|l| l.starts_with("== ")).collect();
    assert_eq!(
        headings,
        [
            "== arena (paper env. 2): the paper's network, eta 0.001, which `h8swarm run arena` runs too",
            "== corridor (paper env. 1): the paper's network, eta 0.1, which `h8swarm run corridor` runs too",
        ],
        "{text}"
    );
    assert!(!text.contains("default network"), "{text}");
    // The measured network is the paper's: η 0.001 is 33 in Q15.
    let arena = &text[..text.find("== corridor").unwrap()];
    assert!(arena.contains(", eta 33 (Q15),"), "{arena}");
    let out = h8swarm(&["fit", "--history", "2", "--steps", "20"]);
    assert!(out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stdout)
            .contains("== what-if, from the paper's network in the arena\n")
    );
}
