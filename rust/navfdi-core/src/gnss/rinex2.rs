//! RINEX 2.11 observation and GPS navigation files as the RINEX 3 text the guarded reader
//! checks and parses ([`super::rinex`]), with a map from each line of the converted text to the
//! original's (errors are reported on the original lines).
//!
//! Observations: the header's `# / TYPES OF OBSERV` becomes one `SYS / # / OBS TYPES` line set
//! per system with the RINEX 3 codes of the RINEX 2 types (GPS `C1`→`C1C`, `P1`→`C1W`,
//! `L1`→`L1C`, `D1`→`D1C`, `S1`→`S1C`, `P2`→`C2W`, `L2`→`L2W`, `D2`→`D2W`, `S2`→`S2W`,
//! `C2`→`C2X`, `C5`/`L5`/`D5`/`S5`→`?5X`; Galileo `C1`→`C1X` …; GLONASS `C1`→`C1C`,
//! `P1`→`C1P`, `P2`→`C2P` …), each epoch line `yy mm dd hh mm ss flag n` + satellite list
//! (continued every 12 satellites) becomes `> yyyy mm dd hh mm ss flag n`, and each
//! satellite's observations (5 per line) one line after its name; a blank system letter is
//! GPS. Navigation (GPS): `ION ALPHA`/`ION BETA` become `GPSA`/`GPSB`, each record's first
//! line `Gnn yyyy …` and its `D` exponents `E`.

use super::rinex_text::{format_err, label, split_header};
use crate::error::Result;

/// RINEX 3 code of RINEX 2 observation type `t` for system `sys`.
fn code3(sys: char, t: &str) -> Option<String> {
    let mut c = t.chars();
    let (kind, band) = (c.next()?, c.next()?);
    let attr = match (sys, kind, band) {
        (_, 'P', '1') | (_, 'P', '2') if sys == 'R' => 'P',
        ('G', 'P', _) => 'W',
        ('G', 'L' | 'D' | 'S', '2') => 'W',
        ('G', 'C', '2') => 'X',
        ('R', _, _) => 'C',
        ('G' | 'J', _, '1') => 'C',
        (_, _, _) => 'X',
    };
    let kind = if kind == 'P' { 'C' } else { kind };
    Some(format!("{kind}{band}{attr}"))
}

/// The RINEX 3 text of a RINEX 2.11 observation file and the original line of each line.
pub(crate) fn obs_to_v3(path: &str, text: &str) -> Result<(String, Vec<usize>)> {
    let (lines, end) = split_header(path, text)?;
    let mut types: Vec<String> = Vec::new();
    let mut file_sys = 'G';
    for l in &lines[..end] {
        match label(l) {
            "RINEX VERSION / TYPE" => {
                file_sys = l.get(40..41).unwrap_or("G").chars().next().unwrap_or('G');
                if file_sys == ' ' {
                    file_sys = 'G';
                }
            }
            "# / TYPES OF OBSERV" => {
                types.extend(
                    l.get(6..60)
                        .unwrap_or("")
                        .split_whitespace()
                        .map(String::from),
                );
            }
            _ => {}
        }
    }
    if types.is_empty() {
        return Err(format_err(
            path,
            None,
            "no '# / TYPES OF OBSERV' header line",
        ));
    }
    // The systems of the satellites in the file.
    let mut systems: Vec<char> = Vec::new();
    let mut out = String::with_capacity(text.len() * 2);
    let mut map = Vec::new();
    let mut body = String::new();
    let mut body_map = Vec::new();
    let n_types = types.len();
    let rows = n_types.div_ceil(5);
    let mut i = end + 1;
    while i < lines.len() {
        let l = lines[i];
        if l.trim().is_empty() {
            i += 1;
            continue;
        }
        let bad = |what: &str| format_err(path, Some(i + 1), what.to_string());
        let yy: i32 = l
            .get(1..3)
            .unwrap_or("")
            .trim()
            .parse()
            .map_err(|_| bad("expected an epoch line (yy mm dd hh mm ss flag n)"))?;
        let flag = l.get(28..29).unwrap_or(" ");
        let n: usize = l
            .get(29..32)
            .unwrap_or("")
            .trim()
            .parse()
            .map_err(|_| bad("the epoch line has no satellite count"))?;
        let year = if yy < 80 { 2000 + yy } else { 1900 + yy };
        if !(flag == "0" || flag == "1") {
            // Event records (flags 2–5): the next n lines are header-like records; skip them.
            i += 1 + n;
            continue;
        }
        let mut sats: Vec<String> = Vec::with_capacity(n);
        let mut j = i;
        while sats.len() < n {
            let src = lines.get(j).copied().unwrap_or("");
            for k in 0..12 {
                if sats.len() == n {
                    break;
                }
                let f = src.get(32 + 3 * k..35 + 3 * k).unwrap_or("");
                if f.trim().is_empty() {
                    return Err(format_err(
                        path,
                        Some(j + 1),
                        format!("{n} satellites announced, {} listed", sats.len()),
                    ));
                }
                let sys = f.chars().next().filter(|c| *c != ' ').unwrap_or('G');
                let prn: u32 = f.get(1..).unwrap_or("").trim().parse().map_err(|_| {
                    format_err(path, Some(j + 1), format!("'{f}' is not a satellite"))
                })?;
                if !systems.contains(&sys) {
                    systems.push(sys);
                }
                sats.push(format!("{sys}{prn:02}"));
            }
            j += 1;
        }
        body.push_str(&format!(
            "> {year:04}{}  {flag}{n:>3}\n",
            l.get(3..26).unwrap_or("")
        ));
        body_map.push(i + 1);
        let mut k = j;
        // A file cut inside an epoch: fewer observation lines than its satellites need.
        if k + rows * n > lines.len() {
            let have = lines.len().saturating_sub(k) / rows.max(1);
            return Err(format_err(
                path,
                Some(i + 1),
                format!("the file ends inside this epoch: {n} satellites announced, observations for {have} (truncated?)"),
            ));
        }
        for s in &sats {
            let mut row = s.clone();
            for r in 0..rows {
                let src = lines.get(k + r).copied().unwrap_or("");
                let want = (n_types - 5 * r).min(5);
                row.push_str(&format!("{:<w$}", src, w = 16 * want));
            }
            body.push_str(row.trim_end());
            body.push('\n');
            body_map.push(k + 1);
            k += rows;
        }
        i = k;
    }
    for (n, l) in lines[..end].iter().enumerate() {
        match label(l) {
            "RINEX VERSION / TYPE" => {
                out.push_str(&format!("     3.04           OBSERVATION DATA    {file_sys}                   RINEX VERSION / TYPE\n"));
                map.push(n + 1);
            }
            "# / TYPES OF OBSERV" | "WAVELENGTH FACT L1/2" => {}
            _ => {
                out.push_str(l);
                out.push('\n');
                map.push(n + 1);
            }
        }
    }
    for sys in &systems {
        let codes: Vec<String> = types
            .iter()
            .map(|t| code3(*sys, t).unwrap_or_else(|| "   ".into()))
            .collect();
        for (c, chunk) in codes.chunks(13).enumerate() {
            let head = if c == 0 {
                format!("{sys}  {:>3}", codes.len())
            } else {
                "      ".into()
            };
            let fields: String = chunk.iter().map(|x| format!(" {x}")).collect();
            out.push_str(&format!(
                "{:<60}SYS / # / OBS TYPES\n",
                format!("{head}{fields}")
            ));
            map.push(end);
        }
    }
    out.push_str(&format!("{:60}END OF HEADER\n", ""));
    map.push(end + 1);
    out.push_str(&body);
    map.extend(body_map);
    Ok((out, map))
}

/// The RINEX 3 text of a RINEX 2 GPS navigation file and the original line of each line.
pub(crate) fn nav_to_v3(path: &str, text: &str) -> Result<(String, Vec<usize>)> {
    let (lines, end) = split_header(path, text)?;
    let first = lines[0];
    if first.get(20..21) != Some("N") {
        return Err(format_err(path, Some(1), "a RINEX 2 navigation file must be GPS ('N'); GLONASS ('G') and Galileo files are not read"));
    }
    let mut out = String::with_capacity(text.len() + 1024);
    let mut map = Vec::new();
    let d2e = |s: &str| s.replace(['D', 'd'], "E");
    for (n, l) in lines[..=end].iter().enumerate() {
        let line = match label(l) {
            "RINEX VERSION / TYPE" => {
                "     3.04           N: GNSS NAV DATA    G: GPS              RINEX VERSION / TYPE"
                    .to_string()
            }
            "ION ALPHA" => format!(
                "GPSA {:<55}IONOSPHERIC CORR",
                d2e(l.get(2..50).unwrap_or(""))
            ),
            "ION BETA" => format!(
                "GPSB {:<55}IONOSPHERIC CORR",
                d2e(l.get(2..50).unwrap_or(""))
            ),
            "DELTA-UTC: A0,A1,T,W"
            | "LEAP SECONDS"
            | "END OF HEADER"
            | "PGM / RUN BY / DATE"
            | "COMMENT" => l.to_string(),
            _ => continue,
        };
        out.push_str(&line);
        out.push('\n');
        map.push(n + 1);
    }
    let mut i = end + 1;
    while i < lines.len() {
        let l = lines[i];
        if l.trim().is_empty() {
            i += 1;
            continue;
        }
        let bad = |what: String| format_err(path, Some(i + 1), what);
        let prn: u32 = l.get(0..2).unwrap_or("").trim().parse().map_err(|_| {
            bad(format!(
                "expected a record's first line (PRN yy mm dd …), found '{}'",
                l.trim_end()
            ))
        })?;
        let num = |a: usize, b: usize| -> Result<i64> {
            l.get(a..b)
                .unwrap_or("")
                .trim()
                .parse::<f64>()
                .map(|x| x as i64)
                .map_err(|_| {
                    bad(format!(
                        "the record's epoch field '{}' is not a number",
                        l.get(a..b).unwrap_or("")
                    ))
                })
        };
        let yy = num(3, 5)?;
        let year = if yy < 80 { 2000 + yy } else { 1900 + yy };
        let (mo, d, h, mi, s) = (
            num(6, 8)?,
            num(9, 11)?,
            num(12, 14)?,
            num(15, 17)?,
            num(18, 22)?,
        );
        out.push_str(&format!(
            "G{prn:02} {year:04} {mo:02} {d:02} {h:02} {mi:02} {s:02}{}\n",
            d2e(l.get(22..).unwrap_or(""))
        ));
        map.push(i + 1);
        for k in 1..8 {
            let c = lines.get(i + k).copied().unwrap_or("");
            out.push_str(&format!(" {}\n", d2e(c)));
            map.push(i + k + 1);
        }
        i += 8;
    }
    Ok((out, map))
}
