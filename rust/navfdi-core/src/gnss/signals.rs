//! Which pseudorange signal to use per system: a documented priority over the first-band
//! codes (those the broadcast group delays refer to), the first one the observation file
//! actually holds; a code the user forces must be in the file. A system asked for with no
//! usable code is an error naming what the file contains, never a silent drop.

use super::broadcast::Sys;
use super::rinex::ObsData;
use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// First-band pseudorange codes per system, most preferred first: GPS L1 C/A, then the
/// semi-codeless P(Y) and L1C; Galileo E1 pilot+data combinations (C1C, then C1X as logged by
/// Trimble, u-blox and phones, then B/A/Z); BeiDou B1I; QZSS L1 C/A, then L1C.
pub fn priority(sys: Sys) -> &'static [&'static str] {
    match sys {
        Sys::Gps => &["C1C", "C1W", "C1X", "C1L", "C1S", "C1P", "C1Y"],
        Sys::Galileo => &["C1C", "C1X", "C1B", "C1A", "C1Z"],
        Sys::BeiDou => &["C2I", "C2X", "C2Q"],
        Sys::Qzss => &["C1C", "C1X", "C1L", "C1S", "C1Z"],
        _ => &[],
    }
}

/// Pseudorange observations per system letter and code in `obs` (codes starting with `C`).
pub fn counts(obs: &ObsData) -> BTreeMap<(char, String), usize> {
    // Counted by code index (no string per observation), named at the end.
    let mut by_index: BTreeMap<(char, u16), usize> = BTreeMap::new();
    for ep in &obs.epochs {
        for o in &ep.obs {
            if o.value > 1e6 && o.value < 1e8 {
                *by_index.entry((o.sat.sys.letter(), o.code)).or_default() += 1;
            }
        }
    }
    let mut out: BTreeMap<(char, String), usize> = BTreeMap::new();
    for ((l, c), k) in by_index {
        let code = &obs.codes[c as usize];
        if code.starts_with('C') {
            *out.entry((l, code.clone())).or_default() += k;
        }
    }
    out
}

/// The code per system of `systems`: `forced` where given (it must hold pseudoranges in
/// `obs`), otherwise the first of [`priority`] with pseudoranges in `obs`. Errors name the
/// system and the pseudorange codes the file holds for it.
pub fn select_codes(
    obs: &ObsData,
    systems: &[Sys],
    forced: &[(Sys, String)],
) -> Result<Vec<(Sys, String)>> {
    let n = counts(obs);
    let held = |s: Sys| -> String {
        let v: Vec<String> = n
            .iter()
            .filter(|((l, _), _)| *l == s.letter())
            .map(|((_, c), k)| format!("{c} ({k})"))
            .collect();
        if v.is_empty() {
            "no pseudoranges at all".into()
        } else {
            v.join(", ")
        }
    };
    let mut out = Vec::new();
    for &s in systems {
        let has = |c: &str| n.get(&(s.letter(), c.to_string())).copied().unwrap_or(0) > 0;
        if let Some((_, c)) = forced.iter().find(|(f, _)| *f == s) {
            if !has(c) {
                return Err(Error::Invalid(format!(
                    "codes: {}={c} has no pseudoranges in the observation file; it holds for {}: {}",
                    s.letter(),
                    s.name(),
                    held(s)
                )));
            }
            out.push((s, c.clone()));
            continue;
        }
        match priority(s).iter().find(|c| has(c)) {
            Some(c) => out.push((s, (*c).to_string())),
            None => {
                return Err(Error::Invalid(format!(
                    "{} was asked for (systems), but the observation file has none of its first-band pseudorange codes ({}); it holds: {}",
                    s.name(),
                    priority(s).join(", "),
                    held(s)
                )))
            }
        }
    }
    Ok(out)
}
