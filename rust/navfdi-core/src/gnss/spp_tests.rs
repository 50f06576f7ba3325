//! Unit tests of `spp.rs` (kept beside it to hold its length).

use super::*;

#[test]
fn fault_offsets_and_windows() {
    let sat = Sat::parse("G13").unwrap();
    let f = InjectedFault {
        sat,
        shape: FaultShape::Ramp,
        magnitude: 0.5,
        start: 100.0,
        end: 300.0,
    };
    assert_eq!(f.offset(99.0), 0.0);
    assert_eq!(f.offset(100.0), 0.0);
    assert!((f.offset(110.0) - 5.0).abs() < 1e-12);
    assert_eq!(f.offset(300.0), 0.0);
    let q = InjectedFault {
        shape: FaultShape::Quadratic,
        ..f
    };
    assert!((q.offset(110.0) - 50.0).abs() < 1e-12);
    let bad = InjectedFault { end: 50.0, ..f };
    assert!(bad.validate().is_err());
}

#[test]
fn codes_outside_the_first_band_are_refused() {
    let mut cfg = SppConfig::new(FdeConfig::new(0.01, None).unwrap());
    cfg.codes[0].1 = "C5Q".into();
    let e = cfg.validate().unwrap_err().to_string();
    assert!(e.contains("C5Q"), "{e}");
    cfg.codes[0].1 = "C1C".into();
    cfg.systems = vec![Sys::Glonass];
    assert!(cfg.validate().is_err());
}
