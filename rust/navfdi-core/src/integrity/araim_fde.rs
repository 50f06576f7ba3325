//! ARAIM fault detection and exclusion ([`araim_fde`]): the solution separation tests of
//! [`super::araim`] on residuals, exclusion candidates recomputed, the levels after exclusion.

use super::araim::{araim_inner, Allocation, AraimResult, Ism};
use crate::error::{Error, Result};

/// ARAIM fault detection and exclusion of one epoch ([`araim_fde`]).
#[derive(Debug, Clone, PartialEq)]
pub struct AraimFde {
    /// The all-in-view result; its modes carry their solution separations.
    pub all_in_view: AraimResult,
    /// Largest `|Δ_k,q| / T_k,q` over the modes and axes (> 1: a test failed).
    pub test_ratio: f64,
    /// A solution separation test failed.
    pub detected: bool,
    /// Satellites excluded (indices into the inputs): the passing candidate with the smallest
    /// test ratio; empty without detection or when no candidate passes.
    pub excluded: Vec<usize>,
    /// Exclusion candidates tried (single satellites and whole constellations; those whose
    /// mode failed its test, then the others if none of them passed).
    pub tried: usize,
    /// Candidates whose subset passed all of its own tests.
    pub passed: usize,
    /// Protection levels of the output solution (m): the all-in-view levels without a
    /// detection; after an exclusion those of the subset kept, by its own modes and tests;
    /// inf when nothing passes.
    pub vpl: f64,
    /// Horizontal protection level of the output solution (m).
    pub hpl: f64,
    /// The largest levels over every passing candidate tried (m): a bound that also holds if
    /// the candidate excluded was the wrong one (equal to `vpl`, `hpl` when one passes).
    pub vpl_any: f64,
    /// Horizontal counterpart of `vpl_any` (m).
    pub hpl_any: f64,
    /// The output solution's least-squares correction east, north, up (m): the position is
    /// the residuals' linearisation point plus it (the subset kept after an exclusion; NaN
    /// on an alarm).
    pub correction: [f64; 3],
    /// A detection that no exclusion resolves: the position must not be used.
    pub alarm: bool,
    /// The output solution is available (levels finite, unmonitored risk within P_THRES).
    pub available: bool,
}

/// ARAIM with fault detection and exclusion (after Blanch et al.'s baseline algorithm):
/// the solution separation test `|Δ_k,q| ≤ T_k,q` for every mode k and axis q on the
/// residuals `y` (n, m; any residuals of the linearised model, e.g. the all-in-view
/// least-squares residuals: the separations do not depend on the linearisation point). On a
/// detection, each single satellite and each whole constellation is a candidate, those whose
/// own mode failed its test first (the others only when none of these passes): ARAIM is
/// recomputed on the subset without it (its own modes, thresholds and levels, the same
/// allocation), and the candidate passes when all of the subset's tests pass. The smallest
/// passing exclusion (single satellites before constellations; then the smallest test ratio)
/// is excluded and its subset's levels are the output's; `vpl_any`/`hpl_any` are the largest
/// over all passing candidates, which also bound a wrong exclusion. Not budgeted: the
/// probability of a wrong exclusion beyond that maximum, and exclusions of more than one
/// event (the candidates are single events; two faults in different constellations alarm).
pub fn araim_fde(
    rows: &[[f64; 3]],
    constellation: &[usize],
    ism: &Ism,
    alloc: &Allocation,
    residuals: &[f64],
) -> Result<AraimFde> {
    let n = rows.len();
    if residuals.len() != n {
        return Err(Error::Shape {
            name: "residuals".into(),
            expected: format!("({n},), one per satellite"),
            got: format!("({},)", residuals.len()),
        });
    }
    if let Some((i, y)) = residuals.iter().enumerate().find(|(_, y)| !y.is_finite()) {
        return Err(Error::InvalidParameter {
            name: format!("residuals[{i}]"),
            value: *y,
            requirement: "residuals must be finite".into(),
        });
    }
    let r0 = araim_inner(rows, constellation, ism, alloc, Some(residuals))?;
    let ratio = |r: &AraimResult| -> f64 {
        r.modes
            .iter()
            .flat_map(|m| (0..3).map(move |q| m.separation[q].abs() / m.threshold[q].max(1e-300)))
            .fold(0.0, f64::max)
    };
    let test_ratio = ratio(&r0);
    if test_ratio <= 1.0 {
        return Ok(AraimFde {
            test_ratio,
            detected: false,
            excluded: Vec::new(),
            tried: 0,
            passed: 0,
            vpl: r0.vpl,
            hpl: r0.hpl,
            vpl_any: r0.vpl,
            hpl_any: r0.hpl,
            correction: r0.correction,
            alarm: false,
            available: r0.available,
            all_in_view: r0,
        });
    }
    // Candidates: each satellite, each constellation (all of its satellites).
    let nc = constellation.iter().copied().max().map_or(0, |m| m + 1);
    let mut candidates: Vec<Vec<usize>> = (0..n).map(|i| vec![i]).collect();
    for c in 0..nc {
        let sats: Vec<usize> = (0..n).filter(|&i| constellation[i] == c).collect();
        if sats.len() > 1 {
            candidates.push(sats);
        }
    }
    // The candidates whose own mode failed its test first; the others only if none of those
    // passes (a fault's mode is normally among the flagged ones: trying all 40 subsets of a
    // 40-satellite epoch costs 40 ARAIM runs).
    let flagged = |cand: &Vec<usize>| {
        r0.modes.iter().any(|m| {
            &m.satellites == cand && (0..3).any(|q| m.separation[q].abs() > m.threshold[q])
        })
    };
    let (first, second): (Vec<Vec<usize>>, Vec<Vec<usize>>) =
        candidates.into_iter().partition(|c| flagged(c));
    // The best passing candidate so far: (size, test ratio, satellites, its ARAIM).
    let mut best: Option<(usize, f64, Vec<usize>, AraimResult)> = None;
    let (mut vpl_any, mut hpl_any, mut passed, mut tried) = (0.0f64, 0.0f64, 0, 0);
    for cand in first.iter().chain(second.iter()) {
        if passed > 0 && tried >= first.len() {
            break;
        }
        tried += 1;
        let keep: Vec<usize> = (0..n).filter(|i| !cand.contains(i)).collect();
        // Constellations re-indexed over the satellites kept.
        let mut map = vec![usize::MAX; nc];
        let mut p_const = Vec::new();
        for &i in &keep {
            let c = constellation[i];
            if map[c] == usize::MAX {
                map[c] = p_const.len();
                p_const.push(ism.p_const[c]);
            }
        }
        let pick = |v: &[f64]| keep.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        let sub_ism = Ism {
            c_int: pick(&ism.c_int),
            c_acc: pick(&ism.c_acc),
            b_nom: pick(&ism.b_nom),
            p_sat: pick(&ism.p_sat),
            p_const,
        };
        let sub_rows: Vec<[f64; 3]> = keep.iter().map(|&i| rows[i]).collect();
        let sub_cons: Vec<usize> = keep.iter().map(|&i| map[constellation[i]]).collect();
        let y = pick(residuals);
        let Ok(r) = araim_inner(&sub_rows, &sub_cons, &sub_ism, alloc, Some(&y)) else {
            continue;
        };
        let rk = ratio(&r);
        if rk > 1.0 || r.modes.is_empty() {
            continue;
        }
        passed += 1;
        vpl_any = vpl_any.max(r.vpl);
        hpl_any = hpl_any.max(r.hpl);
        let better = match &best {
            None => true,
            Some((size, ratio, ..)) => (cand.len(), rk) < (*size, *ratio),
        };
        if better {
            best = Some((cand.len(), rk, cand.clone(), r));
        }
    }
    Ok(match best {
        Some((_, _, excluded, r)) => AraimFde {
            test_ratio,
            detected: true,
            excluded,
            tried,
            passed,
            vpl: r.vpl,
            hpl: r.hpl,
            vpl_any,
            hpl_any,
            correction: r.correction,
            alarm: false,
            available: r.available,
            all_in_view: r0,
        },
        None => AraimFde {
            test_ratio,
            detected: true,
            excluded: Vec::new(),
            tried,
            passed: 0,
            vpl: f64::INFINITY,
            hpl: f64::INFINITY,
            vpl_any: f64::INFINITY,
            hpl_any: f64::INFINITY,
            correction: [f64::NAN; 3],
            alarm: true,
            available: false,
            all_in_view: r0,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrity::araim::araim;
    use crate::integrity::araim::tests::{add_example, sky};

    /// Residuals of the ADD example's geometry for a receiver offset (east, north, up, one
    /// clock per constellation) plus `bias` on some satellites.
    fn residuals(rows: &[[f64; 3]], cons: &[usize], bias: &[(usize, f64)]) -> Vec<f64> {
        let x = [3.0, -2.0, 5.0];
        let clk = [40.0, -25.0];
        let mut y: Vec<f64> = rows
            .iter()
            .zip(cons)
            .map(|(r, &c)| r[0] * x[0] + r[1] * x[1] + r[2] * x[2] + clk[c])
            .collect();
        for &(i, b) in bias {
            y[i] += b;
        }
        y
    }

    #[test]
    fn fde_passes_consistent_residuals_and_keeps_the_levels() {
        let (rows, cons, ism, _) = add_example();
        let alloc = Allocation::lpv200();
        let plain = araim(&rows, &cons, &ism, &alloc).unwrap();
        // Any receiver offset: the separations do not depend on the linearisation point.
        let r = araim_fde(&rows, &cons, &ism, &alloc, &residuals(&rows, &cons, &[])).unwrap();
        assert!(!r.detected && !r.alarm && r.excluded.is_empty());
        assert!(r.test_ratio < 1e-9, "{}", r.test_ratio);
        // The correction recovers the receiver offset the residuals were made with.
        for (c, want) in r.correction.iter().zip([3.0, -2.0, 5.0]) {
            assert!((c - want).abs() < 1e-9, "{:?}", r.correction);
        }
        assert_eq!((r.vpl, r.hpl), (plain.vpl, plain.hpl));
        // A bias under every threshold is not detected either.
        let small = araim_fde(
            &rows,
            &cons,
            &ism,
            &alloc,
            &residuals(&rows, &cons, &[(2, 1.0)]),
        )
        .unwrap();
        assert!(!small.detected && small.test_ratio > 0.0 && small.test_ratio < 1.0);
    }

    #[test]
    fn fde_excludes_the_faulty_satellite_and_recomputes_the_levels() {
        let (rows, cons, ism, _) = add_example();
        let alloc = Allocation::lpv200();
        for faulty in 0..rows.len() {
            let y = residuals(&rows, &cons, &[(faulty, 60.0)]);
            let r = araim_fde(&rows, &cons, &ism, &alloc, &y).unwrap();
            assert!(
                r.detected && r.test_ratio > 1.0,
                "sat {faulty}: {}",
                r.test_ratio
            );
            assert_eq!(r.excluded, vec![faulty], "sat {faulty}");
            // Without the faulty satellite the offset is recovered exactly.
            for (c, want) in r.correction.iter().zip([3.0, -2.0, 5.0]) {
                assert!((c - want).abs() < 1e-9, "sat {faulty}: {:?}", r.correction);
            }
            assert!(!r.alarm && r.passed >= 1);
            // The levels after exclusion bound those of the subset actually kept.
            let keep: Vec<usize> = (0..rows.len()).filter(|&i| i != faulty).collect();
            let sub = araim(
                &keep.iter().map(|&i| rows[i]).collect::<Vec<_>>(),
                &keep.iter().map(|&i| cons[i]).collect::<Vec<_>>(),
                &Ism {
                    c_int: keep.iter().map(|&i| ism.c_int[i]).collect(),
                    c_acc: keep.iter().map(|&i| ism.c_acc[i]).collect(),
                    b_nom: keep.iter().map(|&i| ism.b_nom[i]).collect(),
                    p_sat: keep.iter().map(|&i| ism.p_sat[i]).collect(),
                    p_const: ism.p_const.clone(),
                },
                &alloc,
            )
            .unwrap();
            assert!(r.vpl >= sub.vpl && r.hpl >= sub.hpl, "sat {faulty}");
            assert!(r.vpl.is_finite() && r.vpl > 0.0);
        }
    }

    #[test]
    fn fde_alarms_when_no_single_exclusion_explains_the_residuals() {
        // Two biased satellites in each constellation: no single satellite or constellation
        // removal leaves a consistent subset.
        let (rows, cons, ism) = sky(20);
        let y = residuals(
            &rows,
            &cons,
            &[(2, 90.0), (4, -70.0), (7, 80.0), (9, -60.0)],
        );
        let r = araim_fde(&rows, &cons, &ism, &Allocation::lpv200(), &y).unwrap();
        assert!(r.detected);
        assert!(r.alarm && r.excluded.is_empty() && r.vpl.is_infinite() && !r.available);
        assert_eq!((r.tried, r.passed), (rows.len() + 2, 0));
        // One of them alone is excluded, with finite levels on 19 satellites.
        let y = residuals(&rows, &cons, &[(7, 80.0)]);
        let r = araim_fde(&rows, &cons, &ism, &Allocation::lpv200(), &y).unwrap();
        assert_eq!(r.excluded, vec![7]);
        assert!(r.available && r.vpl.is_finite() && r.vpl_any >= r.vpl);
    }

    #[test]
    fn fde_refuses_bad_residuals() {
        let (rows, cons, ism, _) = add_example();
        let alloc = Allocation::lpv200();
        assert!(araim_fde(&rows, &cons, &ism, &alloc, &[0.0; 3]).is_err());
        let mut y = vec![0.0; rows.len()];
        y[4] = f64::NAN;
        let e = araim_fde(&rows, &cons, &ism, &alloc, &y).unwrap_err();
        assert!(e.to_string().contains("residuals[4]"), "{e}");
    }
}
