//! The epochs of an RTKLIB solution file (`.pos`) in one pass over its text: the fast path of
//! `navfdi.logs.read_pos`, which reads the header, checks the values and names the file, line
//! and column of bad input itself.
//!
//! The parser accepts only the regular form — every data line with the fields the header
//! names, the time as `yyyy/mm/dd hh:mm:ss.sss` (zero-padded) or GPS week and seconds, plain
//! numbers — and returns `None` for anything else, so that the caller's line-by-line reader
//! (which accepts a few more spellings and words every error) decides. Where it returns a
//! table, the numbers are the caller's to the bit: the same correctly rounded parse of each
//! number and the same order of operations for the time.

/// Seconds in a GPS week.
const WEEK: f64 = 604_800.0;

/// The data rows of a `.pos` file's text: `None` unless every line is either a header line
/// (`%…`), blank, or `GPST` time plus at least `n_fields` numbers (further fields are
/// ignored). Returns `(values, lines)`: per data row its time (GPS seconds since 1980-01-06)
/// and its first `n_fields` numbers, row-major `rows × (1 + n_fields)`, and its 1-based line
/// number in the text.
pub fn pos_rows(text: &str, n_fields: usize) -> Option<(Vec<f64>, Vec<u64>)> {
    // Python's `splitlines` and `split` also break at these; such a text goes the slow way.
    let unusual = |c: char| {
        matches!(
            c,
            '\u{b}' | '\u{c}' | '\u{1c}'..='\u{1f}' | '\u{85}' | '\u{2028}' | '\u{2029}'
        )
    };
    if text.contains(unusual) {
        return None;
    }
    let mut values = Vec::new();
    let mut lines = Vec::new();
    for (i, raw) in text.split('\n').enumerate() {
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        if line.contains('\r') {
            return None; // a lone carriage return is a line break for Python
        }
        if line.starts_with('%') || line.trim().is_empty() {
            continue;
        }
        let mut tok = line.split_whitespace();
        let (t0, t1) = (tok.next()?, tok.next()?);
        values.push(gpst(t0, t1)?);
        for _ in 0..n_fields {
            values.push(tok.next()?.parse::<f64>().ok()?);
        }
        lines.push(i as u64 + 1);
    }
    Some((values, lines))
}

/// GPS seconds of a `.pos` time (`navfdi._logtime.pos_time`'s arithmetic), in its regular
/// spellings only.
fn gpst(t0: &str, t1: &str) -> Option<f64> {
    if t0.contains('/') {
        let day = day_start(t0)?;
        let mut hms = t1.split(':');
        let (h, m, s) = (hms.next()?, hms.next()?, hms.next()?);
        if hms.next().is_some()
            || !digits(h)
            || !digits(m)
            || !s.starts_with(|c: char| c.is_ascii_digit())
        {
            return None;
        }
        let (h, m, sec) = (
            h.parse::<u32>().ok()?,
            m.parse::<u32>().ok()?,
            s.parse::<f64>().ok()?,
        );
        if !(h < 24 && m < 60 && (0.0..61.0).contains(&sec)) {
            return None;
        }
        return Some(day + f64::from(h) * 3600.0 + f64::from(m) * 60.0 + sec);
    }
    // Week and seconds: plain numbers (a first field with a sign or a letter goes the slow way).
    if !t0.starts_with(|c: char| c.is_ascii_digit()) {
        return None;
    }
    Some(t0.parse::<f64>().ok()? * WEEK + t1.parse::<f64>().ok()?)
}

fn digits(s: &str) -> bool {
    !s.is_empty() && s.len() <= 9 && s.bytes().all(|b| b.is_ascii_digit())
}

/// GPS seconds of 00:00 GPST on a zero-padded `yyyy/mm/dd` date (the calendar is hifitime's,
/// through the rinex crate; an impossible date is None).
fn day_start(date: &str) -> Option<f64> {
    use rinex::prelude::{Epoch, TimeScale};
    let b = date.as_bytes();
    if b.len() != 10 || b[4] != b'/' || b[7] != b'/' {
        return None;
    }
    let num = |r: std::ops::Range<usize>| -> Option<u16> {
        let s = &date[r];
        digits(s).then(|| s.parse().ok())?
    };
    let (y, m, d) = (num(0..4)?, num(5..7)?, num(8..10)?);
    if y == 0 {
        return None; // Python's calendar starts at year 1
    }
    let (m, d) = (u8::try_from(m).ok()?, u8::try_from(d).ok()?);
    let day = Epoch::maybe_from_gregorian(i32::from(y), m, d, 0, 0, 0, 0, TimeScale::GPST).ok()?;
    Some(day.to_gpst_seconds())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_both_time_forms_and_skips_headers_and_blanks() {
        let text = "% header\n%  GPST  lat lon\n\n1980/01/06 00:00:01.500 40.5 -105.25 3\n2165 345600.25  1e-3 2\n";
        let (v, lines) = pos_rows(text, 2).unwrap();
        assert_eq!(
            v,
            vec![1.5, 40.5, -105.25, 2165.0 * WEEK + 345_600.25, 1e-3, 2.0]
        );
        assert_eq!(lines, vec![4, 5]);
    }

    #[test]
    fn dates_match_the_calendar() {
        // 2025-07-08 is GPS week 2374, day 2 (Tuesday).
        assert_eq!(
            day_start("2025/07/08"),
            Some((2374.0 * 7.0 + 2.0) * 86_400.0)
        );
        assert_eq!(
            day_start("2000/02/29"),
            Some(day_start("2000/02/28").unwrap() + 86_400.0)
        );
        for bad in [
            "2001/02/29",
            "2025/13/01",
            "2025/7/08",
            "25/07/08",
            "2025-07-08",
            "2025/00/10",
        ] {
            assert_eq!(day_start(bad), None, "{bad}");
        }
    }

    #[test]
    fn irregular_text_goes_the_slow_way() {
        for text in [
            "2025/07/08 10:00:00 1 2\n2025/07/08 10:00:01 1\n", // a field short
            "2025/07/08 10:00:00 1 x\n",                        // not a number
            "2025/07/08 24:00:00 1 2\n",                        // hour out of range
            "2025/07/08 10:00:+1 1 2\n",                        // signed seconds
            "2025/07/08 10:00:00 1_0 2\n",                      // Python reads 1_0, Rust does not
            "2025/07/08 10:00:00 1 2\r2025/07/08 10:00:01 1 2\n", // a lone CR
            "2025/07/08 10:00:00 1\u{1f}2\n",                   // a separator Python splits at
            "-5 100 1 2\n",
        ] {
            assert_eq!(pos_rows(text, 2), None, "{text:?}");
        }
        assert!(pos_rows("2025/07/08 10:00:00 1 2 extra\r\n", 2).is_some());
    }
}
