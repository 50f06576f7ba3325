//! Reading a RINEX file's text and checking its structure before the `rinex` crate parses it
//! ([`super::rinex`]): gzip, NUL bytes, non-ASCII data, the version line, the header's end,
//! and the body line by line (epoch and record layout, numbers, time order), so that a
//! malformed file stops with its line and what was expected instead of being dropped or
//! re-ordered silently.

use crate::error::{Error, Result};
use std::collections::HashMap;

pub(crate) fn format_err(path: &str, line: Option<usize>, what: impl std::fmt::Display) -> Error {
    Error::Format(match line {
        Some(l) => format!("{path}, line {l}: {what}"),
        None => format!("{path}: {what}"),
    })
}

/// The lines of `text` (carriage returns removed) and the index of its `END OF HEADER` line.
pub(crate) fn split_header<'a>(path: &str, text: &'a str) -> Result<(Vec<&'a str>, usize)> {
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    let end = lines
        .iter()
        .position(|l| label(l) == "END OF HEADER")
        .ok_or_else(|| format_err(path, None, "no END OF HEADER line"))?;
    Ok((lines, end))
}

/// Label of a header line (columns 61–80), trimmed.
pub(crate) fn label(line: &str) -> &str {
    line.get(60..).map(str::trim).unwrap_or("")
}

/// Read a file's text, gunzipping `.gz` files; errors name the path (not found, unreadable,
/// corrupt gzip, not text). Compact RINEX (Hatanaka) 1 and 3 is expanded
/// (`expand_compact`).
pub fn read_text(path: &str) -> Result<String> {
    let meta = std::fs::metadata(path).map_err(|e| Error::Io(format!("{path}: {e}")))?;
    if meta.is_dir() {
        return Err(Error::Io(format!(
            "{path}: is a directory, not a RINEX file"
        )));
    }
    if !meta.is_file() {
        return Err(Error::Io(format!(
            "{path}: not a regular file (a device, pipe or socket); give the path of a RINEX file"
        )));
    }
    let size = meta.len() as f64;
    // Text, its lines, the normalised copy and the parser's records: about 12 × the text
    // (a gzip file expands about 4 ×).
    let factor = if path.ends_with(".gz") { 48.0 } else { 12.0 };
    crate::memory::check(
        &format!("reading {path}"),
        size * factor,
        &format!("a {} file", crate::memory::human(size)),
        "split the file (e.g. with gfzrnx or teqc) and process the parts",
    )?;
    let mut head = [0u8; 2];
    let gz = {
        use std::io::Read;
        let mut f = std::fs::File::open(path).map_err(|e| Error::Io(format!("{path}: {e}")))?;
        let got = f
            .read(&mut head)
            .map_err(|e| Error::Io(format!("{path}: {e}")))?;
        got == 2 && head == [0x1f, 0x8b]
    };
    // Bounded: a .gz may not inflate beyond crate::memory::MAX_INFLATION times its size.
    let bytes = read_until_nul(path, crate::memory::open_bounded(path)?, gz)?;
    if bytes.is_empty() {
        return Err(format_err(path, None, "the file is empty"));
    }
    // A UTF-8 byte-order mark (an editor's) is not part of the format.
    let bytes = match bytes.strip_prefix(b"\xef\xbb\xbf") {
        Some(rest) => rest.to_vec(),
        None => bytes,
    };
    let compact = bytes.starts_with(b"1.0                 COMPACT RINEX")
        || bytes.starts_with(b"3.0                 COMPACT RINEX");
    let text = String::from_utf8(bytes).map_err(|e| {
        format_err(
            path,
            None,
            format!(
                "not a text file (invalid UTF-8 at byte {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })?;
    if compact {
        return expand_compact(path, &text);
    }
    Ok(text)
}

/// Expand Hatanaka-compressed text (Compact RINEX 1 or 3) to RINEX with the `rinex` crate's
/// decompressor. The header is copied here (without its two CRINEX lines) and the
/// decompressor, built from its observation types, is driven line by line over the records:
/// the crate's `Read` adapter (`DecompressorIO`) does not parse the header and returns 0
/// bytes for an input line that completes no output line, which a reader takes for the end of
/// the file (rinex 0.24).
pub(crate) fn expand_compact(path: &str, text: &str) -> Result<String> {
    use rinex::prelude::{Constellation, Observable};
    use std::collections::HashMap;
    use std::str::FromStr;
    let v3 = text.starts_with("3.0");
    let mut out = String::with_capacity(text.len() * 4);
    let mut lines = text.lines().enumerate();
    let mut codes: HashMap<Constellation, Vec<Observable>> = HashMap::new();
    let mut v2_codes: Vec<Observable> = Vec::new();
    let mut last_sys: Option<Constellation> = None;
    let mut file_sys = Constellation::Mixed;
    let mut ended = false;
    let obs = |c: &str, i: usize| {
        Observable::from_str(c.trim()).map_err(|_| {
            format_err(
                path,
                Some(i + 1),
                format!("unknown observation type '{}'", c.trim()),
            )
        })
    };
    for (i, line) in lines.by_ref() {
        let line = line.trim_end_matches('\r');
        let lab = label(line);
        if lab == "CRINEX VERS   / TYPE" || lab == "CRINEX PROG / DATE" {
            continue;
        }
        out.push_str(line);
        out.push('\n');
        match lab {
            "RINEX VERSION / TYPE" => {
                let c = line.get(40..41).unwrap_or("M").trim();
                file_sys = Constellation::from_str(if c.is_empty() { "G" } else { c })
                    .unwrap_or(Constellation::Mixed);
            }
            "SYS / # / OBS TYPES" => {
                let body = line.get(..60).unwrap_or(line);
                let sys = match body.get(..1).map(str::trim) {
                    Some(c) if !c.is_empty() => {
                        let k = Constellation::from_str(c).map_err(|_| {
                            format_err(path, Some(i + 1), format!("unknown system '{c}'"))
                        })?;
                        last_sys = Some(k);
                        k
                    }
                    _ => last_sys.ok_or_else(|| {
                        format_err(path, Some(i + 1), "observation types without a system")
                    })?,
                };
                let list = codes.entry(sys).or_default();
                for c in body.get(7..).unwrap_or("").split_whitespace() {
                    list.push(obs(c, i)?);
                }
            }
            "# / TYPES OF OBSERV" => {
                let body = line.get(6..60).unwrap_or("");
                for c in body.split_whitespace() {
                    v2_codes.push(obs(c, i)?);
                }
            }
            "END OF HEADER" => {
                ended = true;
                break;
            }
            _ => {}
        }
    }
    if !ended {
        return Err(format_err(
            path,
            None,
            "Compact RINEX: no END OF HEADER line",
        ));
    }
    if !v2_codes.is_empty() {
        for c in [
            Constellation::GPS,
            Constellation::Glonass,
            Constellation::Galileo,
            Constellation::BeiDou,
            Constellation::QZSS,
            Constellation::SBAS,
        ] {
            codes.entry(c).or_insert_with(|| v2_codes.clone());
        }
    }
    let mut dec = rinex::hatanaka::DecompressorExpert::<5>::new(v3, file_sys, codes);
    const CAP: usize = 1 << 16;
    let mut buf = vec![0u8; CAP];
    for (i, line) in lines {
        let line = line.trim_end_matches('\r');
        // The decompressor accepts any text and turns it into numbers (rinex 0.24): refuse a
        // record line with a character no compressed record has (digits, '&', '-', '.', '>',
        // blanks and system letters), unless it carries a header label (an event's records).
        let ok = |c: char| c.is_ascii_digit() || " &-.>GRECJSIM".contains(c);
        let lab = label(line);
        let header_like = lab.chars().any(|c| c.is_ascii_uppercase())
            && lab
                .chars()
                .all(|c| c.is_ascii_uppercase() || " /#".contains(c));
        if !line.chars().all(ok) && !header_like {
            return Err(format_err(
                path,
                Some(i + 1),
                "not Compact RINEX data (a character no compressed record has); the file is damaged",
            ));
        }
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            dec.decompress(line, line.len(), &mut buf, CAP)
        }));
        let size = match caught {
            Ok(Ok(n)) => n,
            Ok(Err(e)) => {
                return Err(format_err(
                    path,
                    Some(i + 1),
                    format!("Compact RINEX (Hatanaka) decompression failed: {e:?}"),
                ))
            }
            Err(_) => {
                return Err(format_err(
                    path,
                    Some(i + 1),
                    "Compact RINEX (Hatanaka) decompression failed on this line",
                ))
            }
        };
        let chunk = std::str::from_utf8(&buf[..size]).map_err(|_| {
            format_err(
                path,
                Some(i + 1),
                "Compact RINEX decompression produced non-text",
            )
        })?;
        if !chunk.is_empty() {
            // Each recovered line (or group of lines) comes without its end of line.
            out.push_str(chunk);
            out.push('\n');
        }
    }
    Ok(out)
}

/// A RINEX 4 navigation file as the RINEX 3 text the reader parses, and for each of its lines
/// the line of the original (1-based). The `> EPH` records whose body has the RINEX 3 layout
/// (GPS/QZSS `LNAV`, Galileo `INAV`/`FNAV`, BeiDou `D1`/`D2`, GLONASS `FDMA`) are kept
/// without their `>` line; the other records (CNAV/CNV1–3 messages, SBAS, system time offsets,
/// Earth orientation, ionosphere models) are left out and counted in the returned number, and
/// the GPS Klobuchar coefficients of the first `> ION G… LNAV` record are returned (they are
/// in the header in RINEX 3).
#[allow(clippy::type_complexity)]
pub(crate) fn rinex4_nav(
    path: &str,
    text: &str,
) -> Result<(String, Vec<usize>, usize, Option<[f64; 8]>)> {
    const KEEP: [&str; 6] = ["LNAV", "INAV", "FNAV", "D1", "D2", "FDMA"];
    let (lines, end) = split_header(path, text)?;
    let mut out = String::with_capacity(text.len());
    let mut map = Vec::with_capacity(lines.len());
    fn push(out: &mut String, map: &mut Vec<usize>, line: &str, orig: usize) {
        out.push_str(line);
        out.push('\n');
        map.push(orig);
    }
    // The Klobuchar record, read first: it goes into the header.
    let mut iono: Option<[f64; 8]> = None;
    for (i, l) in lines.iter().enumerate().skip(end + 1) {
        let f: Vec<&str> = l.split_whitespace().collect();
        if f.len() >= 4 && f[0] == ">" && f[1] == "ION" && f[2].starts_with('G') && f[3] == "LNAV" {
            let mut vals = Vec::new();
            for (j, b) in lines.iter().enumerate().skip(i + 1).take(3) {
                let body = if j == i + 1 {
                    b.get(23..).unwrap_or("")
                } else {
                    b.get(4..).unwrap_or("")
                };
                for k in 0..4 {
                    if vals.len() == 8 {
                        break; // the rest is the region flag
                    }
                    let Some(field) = body.get(k * 19..(k + 1) * 19) else {
                        break;
                    };
                    let field = field.trim();
                    if field.is_empty() {
                        continue;
                    }
                    let v: f64 = field.replace(['D', 'd'], "E").parse().map_err(|_| {
                        format_err(
                            path,
                            Some(j + 1),
                            format!("ionosphere coefficient '{field}' is not a number"),
                        )
                    })?;
                    vals.push(v);
                }
            }
            if vals.len() < 8 {
                return Err(format_err(
                    path,
                    Some(i + 1),
                    "a GPS Klobuchar record (ION LNAV) needs 8 coefficients",
                ));
            }
            let mut k = [0.0; 8];
            k.copy_from_slice(&vals[..8]);
            iono = Some(k);
            break;
        }
    }
    for (i, l) in lines.iter().enumerate().take(end) {
        if i == 0 {
            let rest = l.get(9..).unwrap_or("");
            push(&mut out, &mut map, &format!("{:>9}{rest}", "3.05"), 1);
        } else {
            push(&mut out, &mut map, l, i + 1);
        }
    }
    push(&mut out, &mut map, lines[end], end + 1);
    let mut keep = false;
    let mut started = false;
    let mut dropped = 0usize;
    for (i, l) in lines.iter().enumerate().skip(end + 1) {
        if l.starts_with('>') {
            let f: Vec<&str> = l.split_whitespace().collect();
            keep = f.len() >= 4 && f[1] == "EPH" && KEEP.contains(&f[3]);
            dropped += usize::from(!keep);
            started = true;
            continue;
        }
        if !started && !l.trim().is_empty() {
            return Err(format_err(
                path,
                Some(i + 1),
                "RINEX 4 navigation data must start with a '>' record line",
            ));
        }
        if keep {
            push(&mut out, &mut map, l, i + 1);
        }
    }
    Ok((out, map, dropped, iono))
}

/// Read all of `src`, stopping at the first NUL byte with an error that names its line and
/// byte offset (a file padded or overwritten with zeros is not text; reading on would cost
/// the whole padding in time and memory).
pub(crate) fn read_until_nul(path: &str, mut src: impl std::io::Read, gz: bool) -> Result<Vec<u8>> {
    let mut out: Vec<u8> = Vec::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let got = src.read(&mut buf).map_err(|e| {
            crate::memory::read_error(&e, |e| {
                if gz {
                    format_err(path, None, format!("corrupt or truncated gzip data: {e}"))
                } else {
                    Error::Io(format!("{path}: {e}"))
                }
            })
        })?;
        if got == 0 {
            return Ok(out);
        }
        if let Some(p) = buf[..got].iter().position(|&b| b == 0) {
            let at = out.len() + p;
            out.extend_from_slice(&buf[..p]);
            let line = out.iter().filter(|&&b| b == b'\n').count() + 1;
            return Err(format_err(
                path,
                Some(line),
                format!(
                    "NUL bytes from byte {at}{}: not a text file (padded with zeros or corrupted)",
                    if gz { " of the decompressed data" } else { "" }
                ),
            ));
        }
        out.extend_from_slice(&buf[..got]);
    }
}

/// Refuse a non-ASCII character in the data section (`lines[start..]`), naming its line and
/// column: RINEX data are ASCII, and a corrupted byte would otherwise shift the fixed columns
/// and be reported as a wrong number at the wrong place (or make a parser drop a record).
pub(crate) fn check_ascii(path: &str, lines: &[&str], start: usize) -> Result<()> {
    for (i, line) in lines.iter().enumerate().skip(start) {
        if let Some((c, ch)) = line.chars().enumerate().find(|(_, ch)| !ch.is_ascii()) {
            return Err(format_err(
                path,
                Some(i + 1),
                format!(
                    "column {}: non-ASCII character {ch:?} in the data (RINEX data are ASCII: a corrupted byte?)",
                    c + 1
                ),
            ));
        }
    }
    Ok(())
}

/// A navigation-record number field (`D19.12`, `D` or `E` exponent): blank, or a finite number.
pub(crate) fn nav_field_ok(v: &str) -> bool {
    let v = v.trim();
    v.is_empty()
        || v.replace(['D', 'd'], "E")
            .parse::<f64>()
            .is_ok_and(f64::is_finite)
}

/// Check the first header line: version 3.xx and the file type letter `kind` (`O` or `N`).
pub(crate) fn check_version(path: &str, text: &str, kind: char) -> Result<String> {
    let first = text.lines().next().unwrap_or("");
    if label(first) != "RINEX VERSION / TYPE" {
        return Err(format_err(
            path,
            Some(1),
            "expected the 'RINEX VERSION / TYPE' header line: not a RINEX file",
        ));
    }
    let version = first.get(..9).unwrap_or("").trim().to_string();
    let major = version.split('.').next().unwrap_or("");
    // RINEX 4 observation records have the RINEX 3 layout (navigation files are converted
    // before this check, `rinex4_nav`).
    if !(major == "3" || (major == "4" && kind == 'O')) {
        return Err(format_err(
            path,
            Some(1),
            format!("RINEX version '{version}' is not supported (3.xx and 4.xx are); convert the file to RINEX 3 (e.g. gfzrnx or RTKLIB convbin)"),
        ));
    }
    let t = first
        .get(20..21)
        .unwrap_or(" ")
        .chars()
        .next()
        .unwrap_or(' ');
    if t != kind {
        let what = match t {
            'O' => "an observation file",
            'N' => "a navigation file",
            'M' => "a meteorological file",
            _ => "a file of another kind",
        };
        let want = if kind == 'O' {
            "an observation file (type O)"
        } else {
            "a navigation file (type N)"
        };
        return Err(format_err(
            path,
            Some(1),
            format!("this is {what} (type '{t}'); expected {want}"),
        ));
    }
    Ok(version)
}

/// Index of the line after `END OF HEADER` (0-based), or an error. Every header line must
/// carry its label in columns 61–80.
pub(crate) fn header_end(path: &str, lines: &[&str]) -> Result<usize> {
    let end = lines
        .iter()
        .position(|l| label(l) == "END OF HEADER")
        .map(|i| i + 1)
        .ok_or_else(|| {
            format_err(
                path,
                Some(lines.len()),
                "no 'END OF HEADER' line: the header is truncated or the file is not RINEX",
            )
        })?;
    if let Some(i) = lines[..end].iter().position(|l| label(l).is_empty()) {
        return Err(format_err(
            path,
            Some(i + 1),
            "header line without its label in columns 61–80 (truncated or malformed line)",
        ));
    }
    if let Some(i) = lines[..end].iter().position(|l| l.trim_end().len() > 80) {
        return Err(format_err(
            path,
            Some(i + 1),
            "header line longer than 80 characters (two lines run together?)",
        ));
    }
    Ok(end)
}

/// The structure check of an observation body (see the module docs). Returns the number of
/// epochs with flag 0 or 1.
pub(crate) fn check_obs_body(
    path: &str,
    lines: &[&str],
    start: usize,
    counts: &HashMap<char, usize>,
) -> Result<usize> {
    check_ascii(path, lines, start)?;
    let mut i = start;
    let mut epochs = 0;
    // The previous observation epoch: its time fields and line.
    let mut prev: Option<([f64; 6], usize)> = None;
    while i < lines.len() {
        let line = lines[i];
        if line.trim().is_empty() {
            i += 1;
            continue;
        }
        if !line.starts_with('>') {
            return Err(format_err(
                path,
                Some(i + 1),
                format!(
                    "expected an epoch line starting with '>', found '{}'",
                    line.trim_end()
                ),
            ));
        }
        let flag = line.get(31..32).unwrap_or("").trim();
        let n: usize = line.get(32..35).unwrap_or("").trim().parse().map_err(|_| {
            format_err(
                path,
                Some(i + 1),
                "epoch line: the number of satellites (columns 33–35) is missing or not an integer",
            )
        })?;
        let fields: Vec<&str> = line.get(1..29).unwrap_or("").split_whitespace().collect();
        if fields.len() != 6 || fields.iter().any(|f| f.parse::<f64>().is_err()) {
            return Err(format_err(
                path,
                Some(i + 1),
                "epoch line: expected 'year month day hour minute second' in columns 3–29",
            ));
        }
        let epoch_line = i + 1;
        i += 1;
        match flag {
            "0" | "1" => {
                let mut time = [0.0; 6];
                for (t, f) in time.iter_mut().zip(&fields) {
                    *t = f.parse().unwrap_or(f64::NAN);
                }
                if let Some((p, pl)) = prev {
                    let show = |t: &[f64; 6]| {
                        format!(
                            "{:04}-{:02}-{:02} {:02}:{:02}:{:010.7}",
                            t[0], t[1], t[2], t[3], t[4], t[5]
                        )
                    };
                    match time.partial_cmp(&p) {
                        Some(std::cmp::Ordering::Equal) => {
                            return Err(format_err(
                                path,
                                Some(epoch_line),
                                format!("epoch {} repeats the epoch of line {pl} (duplicate epoch)", show(&time)),
                            ))
                        }
                        Some(std::cmp::Ordering::Less) => {
                            return Err(format_err(
                                path,
                                Some(epoch_line),
                                format!(
                                    "epoch {} is before the epoch of line {pl} ({}): the epochs are not in time order",
                                    show(&time),
                                    show(&p)
                                ),
                            ))
                        }
                        _ => {}
                    }
                }
                prev = Some((time, epoch_line));
                epochs += 1;
                for j in 0..n {
                    let Some(sl) = lines.get(i) else {
                        return Err(format_err(
                            path,
                            Some(lines.len()),
                            format!("the file ends inside the epoch of line {epoch_line}: {n} satellite lines announced, {j} found (truncated file?)"),
                        ));
                    };
                    let sys = sl.chars().next().unwrap_or(' ');
                    let prn_ok = sl
                        .get(1..3)
                        .map(|p| p.trim().parse::<u8>().is_ok())
                        .unwrap_or(false);
                    if !prn_ok || !sys.is_ascii_alphabetic() {
                        return Err(format_err(
                            path,
                            Some(i + 1),
                            format!("expected satellite line {} of {n} of the epoch of line {epoch_line} (e.g. 'G05 …'), found '{}'", j + 1, sl.trim_end()),
                        ));
                    }
                    let nobs = counts.get(&sys).copied().ok_or_else(|| {
                        format_err(path, Some(i + 1), format!("satellite system '{sys}' has no 'SYS / # / OBS TYPES' line in the header"))
                    })?;
                    let body = sl.get(3..).unwrap_or("");
                    let nf = body.len().div_ceil(16);
                    if nf > nobs {
                        return Err(format_err(
                            path,
                            Some(i + 1),
                            format!("{nf} observation fields, but the header lists {nobs} types for system '{sys}'"),
                        ));
                    }
                    for f in 0..nf {
                        let a = 3 + 16 * f;
                        let v = sl.get(a..(a + 14).min(sl.len())).unwrap_or("").trim();
                        if !v.is_empty() && v.parse::<f64>().is_err() {
                            return Err(format_err(
                                path,
                                Some(i + 1),
                                format!("column {}: '{v}' is not a number", a + 1),
                            ));
                        }
                    }
                    i += 1;
                }
            }
            "2" | "3" | "4" | "5" | "6" => {
                if i + n > lines.len() {
                    return Err(format_err(
                        path,
                        Some(lines.len()),
                        format!("the file ends inside the event of line {epoch_line} ({n} lines announced)"),
                    ));
                }
                i += n;
            }
            _ => {
                return Err(format_err(
                    path,
                    Some(epoch_line),
                    format!("epoch flag '{flag}' (column 32) is not 0–6"),
                ))
            }
        }
    }
    if epochs == 0 {
        return Err(format_err(
            path,
            None,
            "no observation epochs after the header",
        ));
    }
    Ok(epochs)
}

/// Continuation lines of a navigation record of system `sys` (RINEX 3.04), or None to accept
/// 3–7 (systems not positioned, whose layout changed between 3.0x revisions).
pub(crate) fn nav_lines(sys: char) -> Option<usize> {
    match sys {
        'G' | 'E' | 'C' | 'J' | 'I' => Some(7),
        _ => None,
    }
}

pub(crate) fn check_nav_body(path: &str, lines: &[&str], start: usize) -> Result<usize> {
    check_ascii(path, lines, start)?;
    let mut i = start;
    let mut records = 0;
    while i < lines.len() {
        let line = lines[i];
        if line.trim().is_empty() {
            i += 1;
            continue;
        }
        let sys = line.chars().next().unwrap_or(' ');
        let prn_ok = line
            .get(1..3)
            .map(|p| p.trim().parse::<u8>().is_ok())
            .unwrap_or(false);
        if !sys.is_ascii_alphabetic() || !prn_ok {
            return Err(format_err(
                path,
                Some(i + 1),
                format!("expected the first line of a navigation record (e.g. 'G05 2024 06 24 …'), found '{}'", line.trim_end()),
            ));
        }
        let first = i + 1;
        let sv = line.get(..3).unwrap_or("").trim();
        // Epoch: year month day hour minute second in columns 5–23.
        let epoch_ok = {
            let f: Vec<&str> = line.get(3..23).unwrap_or("").split_whitespace().collect();
            f.len() == 6 && f.iter().all(|x| x.parse::<u32>().is_ok())
        };
        if !epoch_ok {
            return Err(format_err(
                path,
                Some(first),
                format!(
                    "columns 5–23: '{}' is not an epoch 'year month day hour minute second' (navigation record of {sv})",
                    line.get(3..23).unwrap_or("").trim()
                ),
            ));
        }
        let bad_field = |l: &str, from: usize| -> Option<(usize, String)> {
            (from..80).step_by(19).find_map(|a| {
                let v = l.get(a..(a + 19).min(l.len())).unwrap_or("");
                (!nav_field_ok(v)).then(|| (a + 1, v.trim().to_string()))
            })
        };
        if let Some((col, v)) = bad_field(line, 23) {
            return Err(format_err(
                path,
                Some(first),
                format!("column {col}: '{v}' is not a number (navigation record of {sv})"),
            ));
        }
        i += 1;
        let mut k = 0;
        while i < lines.len() && lines[i].starts_with("    ") && !lines[i].trim().is_empty() {
            if let Some((col, v)) = bad_field(lines[i], 4) {
                return Err(format_err(
                    path,
                    Some(i + 1),
                    format!("column {col}: '{v}' is not a number (navigation record of {sv} at line {first})"),
                ));
            }
            k += 1;
            i += 1;
        }
        let ok = match nav_lines(sys) {
            Some(n) => k == n,
            None => (3..=7).contains(&k),
        };
        if !ok {
            let want = nav_lines(sys).map_or("3–7".to_string(), |n| n.to_string());
            let at_end = i >= lines.len();
            return Err(format_err(
                path,
                Some(first),
                format!(
                    "the record of {} has {k} continuation lines, expected {want}{}",
                    line.get(..3).unwrap_or("").trim(),
                    if at_end { " (truncated file?)" } else { "" }
                ),
            ));
        }
        records += 1;
    }
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(name: &str) -> String {
        format!(
            "{}/../../tests/data/rinex_formats/{name}",
            env!("CARGO_MANIFEST_DIR")
        )
    }

    /// Lines with trailing blanks removed (the plain files pad some lines to 80 columns).
    fn lines(t: &str) -> Vec<String> {
        t.lines().map(|l| l.trim_end().to_string()).collect()
    }

    #[test]
    fn compact_rinex_3_and_1_expand_to_their_plain_pairs() {
        for (crx, plain) in [
            (
                "ACOR00ESP_R_20213550000_01D_30S_MO.crx",
                "ACOR00ESP_R_20213550000_01D_30S_MO.rnx.gz",
            ),
            ("delf0010.21d.gz", "delf0010.21o.gz"),
        ] {
            let a = read_text(&data(crx)).unwrap();
            let b = read_text(&data(plain)).unwrap();
            let (la, lb) = (lines(&a), lines(&b));
            assert_eq!(la.len(), lb.len(), "{crx}");
            for (i, (x, y)) in la.iter().zip(&lb).enumerate() {
                assert_eq!(x, y, "{crx}, line {}", i + 1);
            }
        }
    }

    #[test]
    fn a_broken_compact_file_names_its_line() {
        let text = read_text(&data("ACOR00ESP_R_20213550000_01D_30S_MO.crx")).unwrap();
        let raw = std::fs::read_to_string(data("ACOR00ESP_R_20213550000_01D_30S_MO.crx")).unwrap();
        assert!(text.len() > raw.len());
        // Header without its end: refused with the reason.
        let cut: String = raw
            .lines()
            .take_while(|l| !l.contains("END OF HEADER"))
            .map(|l| format!("{l}\n"))
            .collect();
        let e = expand_compact("x.crx", &cut).unwrap_err().to_string();
        assert!(e.contains("no END OF HEADER"), "{e}");
        // A satellite line that is not compressed data: an error, never a panic.
        let mut bad: Vec<&str> = raw.lines().collect();
        let k = bad.iter().position(|l| l.starts_with('>')).unwrap() + 2;
        bad[k] = "3&x&&y 3&not numbers";
        let joined = bad.join("\n");
        let e = expand_compact("x.crx", &joined).unwrap_err().to_string();
        assert!(
            e.contains(&format!("line {}", k + 1)) && e.contains("damaged"),
            "{e}"
        );
    }
}
