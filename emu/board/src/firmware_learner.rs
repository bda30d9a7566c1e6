//! The firmware's own learner routines, called by their symbols on the H8/300H core.
//!
//! The learner of `firmware/learner.c` works on globals (`net_w`, `net_x`, `net_y`, `net_o`,
//! `net_win`, `net_eta`, `net_threshold`, …), so the emulator can run it on any operands: it
//! loads the image into an MCU with nothing connected, calls `learner_setup` (which carves the
//! arrays for N × M after `.bss`), writes η, T and the weights into RAM, and for every step writes
//! x and calls `learner_forward`, then calls `learner_update` with E (in R0, as GCC passes a
//! 16-bit argument). A call is made as a JSR would make it: the return address is `__exit`
//! (crt0's halt, never reached otherwise) pushed on a stack at the top of RAM, the arguments in
//! ER0–ER2; the run stops when the PC reaches `__exit`. The states of a call are those from the
//! routine's first instruction to its RTS, its callees included: the phase as the profiler
//! counts it inside the running robot.
//!
//! `h8swarm learn --replay FILE --on-core` and the calibration of `nn_q15`'s meter run on this.

use crate::firmware::{Firmware, FirmwareError};
use crate::profile::{PhaseDef, Profiler};
use h8_3052f::mcu::{Mcu, McuConfig, McuError};
use h8_3052f::pins::NullBoard;
use h8300h::bus::Bus;
use h8300h::cpu::{CCR_I, Cpu, CpuError, Event};

/// Most states one call may take before it counts as a runaway (8 s at 25 MHz; the largest
/// learner step takes well under 0.2 M).
pub const CALL_LIMIT_STATES: u64 = 200_000_000;

/// Why a call on the core failed.
#[derive(Debug, thiserror::Error)]
pub enum OnCoreError {
    /// The image lacks a symbol the calls need.
    #[error("the firmware cannot be called")]
    Firmware(#[from] FirmwareError),
    /// The MCU could not be built.
    #[error("building the MCU")]
    Mcu(#[from] McuError),
    /// The core stopped inside the routine.
    #[error("the core stopped in `{routine}`")]
    Cpu {
        /// The routine called.
        routine: &'static str,
        /// The core's error.
        #[source]
        source: CpuError,
    },
    /// The routine halted or slept instead of returning.
    #[error("`{routine}` halted (SLEEP) at PC H'{pc:06X} instead of returning")]
    Halted {
        /// The routine called.
        routine: &'static str,
        /// Where.
        pc: u32,
    },
    /// The routine did not return in time.
    #[error("`{routine}` did not return within {limit} states (PC H'{pc:06X})")]
    Runaway {
        /// The routine called.
        routine: &'static str,
        /// The bound.
        limit: u64,
        /// Where it was.
        pc: u32,
    },
    /// A shape the firmware's routines do not take.
    #[error(
        "{n_in} inputs x {n_out} outputs: the firmware's learner takes 1 to 256 inputs and 2 to 8 outputs"
    )]
    Shape {
        /// N.
        n_in: usize,
        /// M.
        n_out: usize,
    },
}

#[derive(Clone, Copy, Debug)]
struct Addrs {
    setup: u32,
    step: u32,
    forward: u32,
    update: u32,
    exit: u32,
    heap: u32,
    stack_top: u32,
    net_w: u32,
    net_x: u32,
    net_y: u32,
    net_o: u32,
    net_win: u32,
    net_eta: u32,
    net_threshold: u32,
    net_history: u32,
    net_bias: u32,
}

/// What one forward pass gave.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Forward {
    /// The sums y (Q22).
    pub y: Vec<i32>,
    /// The outputs O (Q15).
    pub o: Vec<i16>,
    /// The winner.
    pub win: usize,
    /// States of `learner_forward`.
    pub states: u64,
}

/// States of one `learner_step` by phase.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepStates {
    /// `learner_step`'s own states (D, E, the input vector, the two calls).
    pub input: u64,
    /// `learner_update`.
    pub update: u64,
    /// `learner_forward`.
    pub forward: u64,
}

/// The firmware's learner on the core, called routine by routine.
#[derive(Debug)]
pub struct LearnerOnCore {
    mcu: Mcu<NullBoard>,
    cpu: Cpu,
    a: Addrs,
    n_in: usize,
    n_out: usize,
    profiler: Profiler,
    /// Where `learner_step`'s four proximities are put: a scratch area below the stack.
    p_addr: u32,
}

impl LearnerOnCore {
    /// Loads `fw` into a fresh MCU (the learner needs nothing connected).
    ///
    /// # Errors
    /// A missing symbol, or an image that does not load.
    pub fn new(fw: &Firmware) -> Result<Self, OnCoreError> {
        let a = Addrs {
            setup: fw.addr("learner_setup")?,
            step: fw.addr("learner_step")?,
            forward: fw.addr("learner_forward")?,
            update: fw.addr("learner_update")?,
            exit: fw.addr("_exit")?,
            heap: fw.addr("_heap_start")?,
            stack_top: fw.addr("_stack_top")?,
            net_w: fw.addr("net_w")?,
            net_x: fw.addr("net_x")?,
            net_y: fw.addr("net_y")?,
            net_o: fw.addr("net_o")?,
            net_win: fw.addr("net_win")?,
            net_eta: fw.addr("net_eta")?,
            net_threshold: fw.addr("net_threshold")?,
            net_history: fw.addr("net_history")?,
            net_bias: fw.addr("net_bias")?,
        };
        let mut mcu = Mcu::new(McuConfig::default(), NullBoard)?;
        mcu.load_image(&fw.image).map_err(FirmwareError::Load)?;
        let phases = [
            PhaseDef::new("input", &["learner_step"]),
            PhaseDef::new("update", &["learner_update"]),
            PhaseDef::new("forward", &["learner_forward"]),
        ];
        let profiler = Profiler::new(&fw.symbols, &phases, "caller").map_err(|e| {
            FirmwareError::MissingSymbol(format!("{} (phase {})", e.function, e.phase))
        })?;
        Ok(LearnerOnCore {
            mcu,
            cpu: Cpu::new(),
            p_addr: a.stack_top - 256,
            a,
            n_in: 0,
            n_out: 0,
            profiler,
        })
    }

    fn poke16(&mut self, addr: u32, v: u16) {
        self.mcu.poke(addr, &v.to_be_bytes());
    }

    fn peek16(&self, addr: u32) -> u16 {
        u16::from_be_bytes([self.mcu.peek(addr), self.mcu.peek(addr + 1)])
    }

    fn peek32(&self, addr: u32) -> u32 {
        (u32::from(self.peek16(addr)) << 16) | u32::from(self.peek16(addr + 2))
    }

    /// Calls the routine at `entry` with `args` in ER0, ER1, ER2, as a JSR would, and runs it
    /// to its return. Returns the states from its first instruction to its RTS.
    fn call(
        &mut self,
        routine: &'static str,
        entry: u32,
        args: &[u32],
    ) -> Result<u64, OnCoreError> {
        let sp = self.a.stack_top - 4;
        self.mcu
            .poke(sp, &(self.a.exit & 0x00FF_FFFF).to_be_bytes());
        self.cpu.set_er(7, sp);
        for (i, &v) in args.iter().enumerate() {
            self.cpu.set_er(i, v);
        }
        self.cpu.set_ccr(CCR_I);
        self.cpu.set_pc(entry);
        self.profiler.enter_function(entry, self.mcu.now());
        let t0 = self.mcu.now();
        while self.cpu.pc() != self.a.exit {
            let deadline = t0 + CALL_LIMIT_STATES;
            match self
                .profiler
                .run_one(&mut self.cpu, &mut self.mcu, deadline)
                .map_err(|source| OnCoreError::Cpu { routine, source })?
            {
                // A routine that sleeps, halts or resets the chip does not return.
                Event::Halted | Event::Asleep | Event::Reset => {
                    return Err(OnCoreError::Halted {
                        routine,
                        pc: self.cpu.pc(),
                    });
                }
                Event::Executed | Event::Interrupt(_) | Event::Break => {}
            }
            if self.mcu.now() - t0 > CALL_LIMIT_STATES {
                return Err(OnCoreError::Runaway {
                    routine,
                    limit: CALL_LIMIT_STATES,
                    pc: self.cpu.pc(),
                });
            }
        }
        Ok(self.mcu.now() - t0)
    }

    /// `learner_setup(heap, N, M)`, then η, T and the weights (M rows of N, Q15 bits).
    ///
    /// # Errors
    /// [`OnCoreError::Shape`] beyond the routines' bounds; a failing call.
    pub fn setup(
        &mut self,
        n_in: usize,
        n_out: usize,
        eta: i16,
        threshold: i16,
        weights: &[i16],
    ) -> Result<(), OnCoreError> {
        if !(1..=256).contains(&n_in) || !(2..=8).contains(&n_out) || weights.len() != n_in * n_out
        {
            return Err(OnCoreError::Shape { n_in, n_out });
        }
        self.call(
            "learner_setup",
            self.a.setup,
            &[self.a.heap, n_in as u32, n_out as u32],
        )?;
        self.n_in = n_in;
        self.n_out = n_out;
        self.poke16(self.a.net_eta, eta as u16);
        self.poke16(self.a.net_threshold, threshold as u16);
        self.set_weights(weights);
        Ok(())
    }

    /// The input layout `learner_step` builds: history depth and bias.
    pub fn set_layout(&mut self, history: u8, bias: bool) {
        self.mcu.poke(self.a.net_history, &[history]);
        self.mcu.poke(self.a.net_bias, &[u8::from(bias)]);
    }

    /// Overwrites the weights (M rows of N).
    pub fn set_weights(&mut self, weights: &[i16]) {
        let w = self.peek32(self.a.net_w);
        let bytes: Vec<u8> = weights.iter().flat_map(|v| v.to_be_bytes()).collect();
        self.mcu.poke(w, &bytes);
    }

    /// The weights as the firmware holds them (M rows of N).
    #[must_use]
    pub fn weights(&self) -> Vec<i16> {
        let w = self.peek32(self.a.net_w);
        (0..self.n_in * self.n_out)
            .map(|k| self.peek16(w + 2 * k as u32) as i16)
            .collect()
    }

    /// The winner of the last forward pass.
    #[must_use]
    pub fn win(&self) -> usize {
        usize::from(self.mcu.peek(self.a.net_win))
    }

    /// Writes x and runs `learner_forward`.
    ///
    /// # Errors
    /// A failing call.
    pub fn forward(&mut self, x: &[i8]) -> Result<Forward, OnCoreError> {
        let xa = self.peek32(self.a.net_x);
        let bytes: Vec<u8> = x.iter().map(|&v| v as u8).collect();
        self.mcu.poke(xa, &bytes);
        let states = self.call("learner_forward", self.a.forward, &[])?;
        let ya = self.peek32(self.a.net_y);
        let oa = self.peek32(self.a.net_o);
        Ok(Forward {
            y: (0..self.n_out)
                .map(|j| self.peek32(ya + 4 * j as u32) as i32)
                .collect(),
            o: (0..self.n_out)
                .map(|j| self.peek16(oa + 2 * j as u32) as i16)
                .collect(),
            win: self.win(),
            states,
        })
    }

    /// Runs `learner_update(e)` on the last x and winner. Returns its states.
    ///
    /// # Errors
    /// A failing call.
    pub fn update(&mut self, e: i16) -> Result<u64, OnCoreError> {
        self.call("learner_update", self.a.update, &[u32::from(e as u16)])
    }

    /// Runs one whole `learner_step(p)` (D, E, update, input vector, forward pass). Returns
    /// the winner and the states of each phase.
    ///
    /// # Errors
    /// A failing call.
    pub fn step(&mut self, p: [u8; 4]) -> Result<(usize, StepStates), OnCoreError> {
        self.mcu.poke(self.p_addr, &p);
        let before = self.profiler.states().to_vec();
        self.call("learner_step", self.a.step, &[self.p_addr])?;
        let d: Vec<u64> = self
            .profiler
            .states()
            .iter()
            .zip(&before)
            .map(|(a, b)| a - b)
            .collect();
        Ok((
            self.win(),
            StepStates {
                input: d[0],
                update: d[1],
                forward: d[2],
            },
        ))
    }
}
