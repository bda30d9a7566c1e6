//! The interrupt controller through the MCU: among the requests enabled at their source, the
//! higher IPR level wins, then the lower vector number; IPRA/IPRB read back.

use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::periph::adc::{ADCSR, ADCSR_ADIE, ADCSR_ADST};
use h8_3052f::periph::intc::{IPRA, IPRA_ITU0, IPRA_ITU2, IPRB, IPRB_AD, IPRB_SCI1};
use h8_3052f::periph::itu::{CHANNEL_BASE, IMFA, OFF_GRA, OFF_TCR, OFF_TIER, OFF_TSR, TSTR};
use h8_3052f::periph::sci::{SCI1_SCR, SCR_TE, SCR_TIE};
use h8_3052f::pins::NullBoard;
use h8300h::bus::Bus;

/// ITU0 and ITU2 compare match A, the A/D end and SCI1 TXI all requested at once.
fn four_requests() -> Mcu<NullBoard> {
    let mut m = Mcu::new(McuConfig::default(), NullBoard).unwrap();
    for ch in [0, 2] {
        let b = CHANNEL_BASE[ch];
        m.write8(b + OFF_TCR, 0x20);
        m.write16(b + OFF_GRA, 9);
        m.write8(b + OFF_TIER, IMFA);
    }
    m.write8(ADCSR, ADCSR_ADST | ADCSR_ADIE);
    m.write8(TSTR, 0x05);
    m.internal(300);
    m.write8(SCI1_SCR, SCR_TE | SCR_TIE);
    m
}

#[test]
fn lower_vector_wins_at_equal_level() {
    let m = four_requests();
    assert_eq!(m.pending_irq(), Some(24));
}

#[test]
fn a_higher_ipr_level_wins_over_a_lower_vector() {
    let mut m = four_requests();
    m.write8(IPRB, IPRB_AD);
    assert_eq!(
        m.pending_irq(),
        Some(60),
        "ADI at level 1 beats ITU0 at level 0"
    );
    m.write8(IPRB, IPRB_AD | IPRB_SCI1);
    assert_eq!(
        m.pending_irq(),
        Some(58),
        "TXI1 and ADI at level 1: lower vector"
    );
    m.write8(IPRA, IPRA_ITU2);
    assert_eq!(
        m.pending_irq(),
        Some(32),
        "ITU2 at level 1 is the lowest vector there"
    );
    m.write8(IPRA, IPRA_ITU2 | IPRA_ITU0);
    assert_eq!(m.pending_irq(), Some(24));
    assert_eq!(m.read8(IPRA), IPRA_ITU2 | IPRA_ITU0);
    assert_eq!(m.read8(IPRB), IPRB_AD | IPRB_SCI1);
}

#[test]
fn clearing_a_source_hands_over_to_the_next() {
    let mut m = four_requests();
    m.write8(IPRA, IPRA_ITU2);
    assert_eq!(m.pending_irq(), Some(32));
    // Stop the timers and clear ITU2's flag: nothing is left at level 1, so the lowest
    // vector at level 0 wins.
    m.write8(TSTR, 0x00);
    let b = CHANNEL_BASE[2];
    let tsr = m.read8(b + OFF_TSR);
    m.write8(b + OFF_TSR, tsr & !IMFA);
    assert_eq!(m.pending_irq(), Some(24));
    // Disable at the source: masking is per source, flags stay.
    m.write8(CHANNEL_BASE[0] + OFF_TIER, 0);
    assert_eq!(m.pending_irq(), Some(58));
    m.write8(SCI1_SCR, SCR_TE);
    assert_eq!(m.pending_irq(), Some(60));
    m.write8(ADCSR, 0);
    assert_eq!(m.pending_irq(), None);
    assert_ne!(m.read8(CHANNEL_BASE[0] + OFF_TSR) & IMFA, 0);
}
