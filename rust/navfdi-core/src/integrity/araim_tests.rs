//! Tests of [`super`] (ARAIM): the ADD's Appendix D example, the protection-level search,
//! allocations, fault modes and their statistics.

use super::*;

pub(crate) fn add_example() -> (Vec<[f64; 3]>, Vec<usize>, Ism, serde_json::Value) {
    let v: serde_json::Value = serde_json::from_str(include_str!(
        "../../../../tests/data/araim/add_v3_appendix_d.json"
    ))
    .unwrap();
    let mut rows = Vec::new();
    let mut cons = Vec::new();
    let (mut c_int, mut c_acc) = (Vec::new(), Vec::new());
    for r in v["rows"].as_array().unwrap() {
        let name = r[0].as_str().unwrap();
        let g: Vec<f64> = r[1]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        rows.push([g[0], g[1], g[2]]);
        cons.push(usize::from(!name.starts_with('G')));
        c_int.push(r[2].as_f64().unwrap());
        c_acc.push(r[3].as_f64().unwrap());
    }
    let n = rows.len();
    let ism = Ism {
        c_int,
        c_acc,
        b_nom: vec![0.5; n],
        p_sat: vec![1e-5; n],
        p_const: vec![1e-4, 1e-4],
    };
    (rows, cons, ism, v)
}

#[test]
fn reproduces_the_add_appendix_d_example() {
    let (rows, cons, ism, v) = add_example();
    let e = &v["expected"];
    let r = araim(&rows, &cons, &ism, &Allocation::lpv200()).unwrap();
    assert_eq!(
        r.modes.len(),
        e["n_fault_modes_excl_fault_free"].as_u64().unwrap() as usize
    );
    assert!(
        (r.k_fa[2] - e["K_fa_vert"].as_f64().unwrap()).abs() < 5e-4,
        "{}",
        r.k_fa[2]
    );
    for (key, c) in [("const_out_GPS", 0usize), ("const_out_GAL", 1)] {
        let m = r
            .modes
            .iter()
            .find(|m| m.constellations == vec![c])
            .unwrap();
        let want = &e[key];
        assert!(
            (m.sigma[2] - want["sigma_v_m"].as_f64().unwrap()).abs() < 5e-4,
            "{key} σ_v {}",
            m.sigma[2]
        );
        assert!(
            (m.sigma_ss[2] - want["sigma_ss_v_m"].as_f64().unwrap()).abs() < 5e-4,
            "{key} σ_ss {}",
            m.sigma_ss[2]
        );
        assert!(
            (m.bias[2] - want["b_v_m"].as_f64().unwrap()).abs() < 5e-4,
            "{key} b {}",
            m.bias[2]
        );
    }
    for (got, key) in [
        (r.vpl, "VPL_m"),
        (r.hpl, "HPL_m"),
        (r.emt, "EMT_m"),
        (r.sigma_acc[2], "sigma_acc_v_m"),
    ] {
        assert!(
            (got - e[key].as_f64().unwrap()).abs() < 0.05,
            "{key}: {got}"
        );
    }
    assert!(r.available && r.p_unmonitored < 8e-8);
}

#[test]
fn the_add_search_returns_a_level_within_tol_pl_above_the_root() {
    // The ADD's half-interval search stops with a bracket at most TOL_PL wide and returns
    // its upper end: at or above the exact root (1 µm), by less than TOL_PL per axis. On
    // the Appendix D example the roots are VPL 19.2171 m, HPL 14.4158 m (east 9.5226,
    // north 10.8230 m); the ADD publishes 19.2 and 14.5 m.
    let (rows, cons, ism, _) = add_example();
    let exact = Allocation {
        tol_pl: 0.0,
        ..Allocation::lpv200()
    };
    let root = araim(&rows, &cons, &ism, &exact).unwrap();
    assert!((root.vpl - 19.2171).abs() < 1e-3 && (root.hpl - 14.4158).abs() < 1e-3);
    for tol in [0.05, 0.5, 2.0] {
        let alloc = Allocation {
            tol_pl: tol,
            ..Allocation::lpv200()
        };
        let r = araim(&rows, &cons, &ism, &alloc).unwrap();
        assert!(
            r.vpl >= root.vpl - 1e-6 && r.vpl <= root.vpl + tol,
            "{tol}: {}",
            r.vpl
        );
        // HPL = hypot(east, north), each within tol above its root.
        assert!(
            r.hpl >= root.hpl - 1e-6 && r.hpl <= root.hpl + tol * std::f64::consts::SQRT_2,
            "{tol}: {}",
            r.hpl
        );
    }
}

/// A deterministic uniform draw in [0, 1) (a 64-bit LCG's top 53 bits) from `seed`.
fn uniform_from(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn the_replayed_add_search_returns_the_plain_searchs_level_bit_for_bit() {
    // add_level replays the half-interval search from the root instead of evaluating f at
    // every midpoint; the plain search (f at every midpoint, as the ADD writes it) must
    // end on the same bits, for modes of every size, including a midpoint that lands
    // next to the root (tol chosen so), and brackets the root is outside of.
    let plain = |b0: f64, s0: f64, terms: &[(f64, f64, f64)], target: f64, tol: f64| {
        // add_level's search as it was before the replay, from the same bracket.
        let all = || std::iter::once((2.0, b0, 1.0 / s0)).chain(terms.iter().copied());
        let (mut lo, mut hi) = add_bracket(b0, s0, terms, target);
        let f = |l: f64| -> f64 { all().map(|(p, shift, inv)| p * q((l - shift) * inv)).sum() };
        let mut count = 0;
        while hi - lo > tol && count < 200 {
            let half = 0.5 * (lo + hi);
            if f(half) > target {
                lo = half;
            } else {
                hi = half;
            }
            count += 1;
        }
        hi
    };
    let mut uniform = uniform_from(7);
    for case in 0..300 {
        let k = 1 + case % 40;
        let terms: Vec<(f64, f64, f64)> = (0..k)
            .map(|_| {
                (
                    10f64.powf(-3.0 - 8.0 * uniform()),
                    10.0 * uniform(),
                    1.0 / (0.3 + 3.0 * uniform()),
                )
            })
            .collect();
        let (b0, s0) = (uniform(), 0.5 + uniform());
        let target = 10f64.powf(-9.0 + 3.0 * uniform());
        let tol = [0.05, 0.5, 1e-4, 2.0][case % 4];
        let got = add_level(b0, s0, &terms, target, tol);
        let want = plain(b0, s0, &terms, target, tol);
        assert_eq!(
            got.to_bits(),
            want.to_bits(),
            "case {case}: {got} against {want}"
        );
    }
}

#[test]
fn the_root_search_leaves_out_only_terms_below_its_floor() {
    // Priors of satellites, pairs and constellations; shifts and σ of 40-satellite modes.
    let mut uniform = uniform_from(11);
    let (mut dropped, mut total) = (0, 0);
    for _ in 0..50 {
        let terms: Vec<(f64, f64, f64)> = (0..200)
            .map(|_| {
                (
                    [1e-5, 1e-10, 1e-4, 1e-9][(4.0 * uniform()) as usize],
                    4.0 * uniform(),
                    1.0 / (0.3 + 1.2 * uniform()),
                )
            })
            .collect();
        let target = 10f64.powf(-9.0 + 3.0 * uniform());
        let lo = 4.0 + 5.0 * uniform();
        let kept = root_terms(&terms, target, lo);
        total += terms.len();
        dropped += terms.len() - kept.len();
        for t in &terms {
            if kept.contains(t) {
                continue;
            }
            let (p, shift, inv) = *t;
            for l in [lo, lo + 0.5, lo + 5.0] {
                let v = p * q((l - shift) * inv);
                assert!(v <= 1e-16 * target, "{t:?} at {l}: {v:e} above the floor");
            }
        }
    }
    // The rule does leave terms out (else the test above proves nothing).
    assert!(dropped > total / 10, "{dropped} of {total} left out");
    // NaN is kept.
    assert_eq!(root_terms(&[(1e-10, f64::NAN, 1.0)], 1e-7, 5.0).len(), 1);
}

#[test]
fn a_bad_allocation_is_refused_by_name() {
    let (rows, cons, ism, _) = add_example();
    for (alloc, name) in [
        (
            Allocation {
                p_hmi_vert: f64::NAN,
                ..Allocation::lpv200()
            },
            "p_hmi_vert",
        ),
        (
            Allocation {
                p_fa_hor: 0.0,
                ..Allocation::lpv200()
            },
            "p_fa_hor",
        ),
        (
            Allocation {
                tol_pl: -0.1,
                ..Allocation::lpv200()
            },
            "tol_pl",
        ),
    ] {
        let e = araim(&rows, &cons, &ism, &alloc).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
}

/// n satellites spread over the sky (golden-angle azimuths, elevations 10–85°), even
/// indices GPS and odd Galileo, with a plain ISM (C_int 1, C_acc 0.6 m², P_const 1e-4).
pub(crate) fn sky(n: usize) -> (Vec<[f64; 3]>, Vec<usize>, Ism) {
    let mut rows = Vec::new();
    let mut cons = Vec::new();
    for i in 0..n {
        let az = (i as f64) * 2.399_963; // golden angle
        let el = (10.0 + 75.0 * ((i * 7 % n) as f64) / (n - 1) as f64).to_radians();
        rows.push([-el.cos() * az.sin(), -el.cos() * az.cos(), -el.sin()]);
        cons.push(i % 2);
    }
    let ism = Ism {
        c_int: vec![1.0; n],
        c_acc: vec![0.6; n],
        b_nom: vec![0.5; n],
        p_sat: vec![1e-5; n],
        p_const: vec![1e-4, 1e-4],
    };
    (rows, cons, ism)
}

#[test]
fn thirty_satellites_monitor_the_combined_modes() {
    // 15 GPS and 15 Galileo satellites spread over the sky, P_const = 1e-4 each: one event
    // at a time leaves P(two or more) = 1.2e-7 > P_THRES unmonitored, so every pair of
    // events (a constellation with a satellite of the other, two satellites, …) is a mode.
    let (rows, cons, ism) = sky(30);
    let r = araim(&rows, &cons, &ism, &Allocation::lpv200()).unwrap();
    assert_eq!(r.n_max, 2);
    assert!(r.p_unmonitored < 8e-8, "{}", r.p_unmonitored);
    assert!(
        r.modes
            .iter()
            .any(|m| m.constellations.len() == 1 && m.satellites.len() == 16),
        "constellation + satellite of the other"
    );
    assert!(
        r.available && r.vpl.is_finite() && r.vpl < 35.0,
        "{} {}",
        r.available,
        r.vpl
    );
}
