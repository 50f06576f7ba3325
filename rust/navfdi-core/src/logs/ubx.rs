//! u-blox binary logs (`.ubx`): the receiver's own navigation solutions (UBX-NAV-PVT, class
//! 0x01 id 0x07) read with the `ublox` crate's parser, every other message skipped. The
//! receiver's other output (raw measurements, ephemerides, NMEA or RTCM interleaved) is not
//! read here: raw measurements go through RINEX (RTKLIB's `convbin`).
//!
//! Time: NAV-PVT carries the GPS time of week (`iTOW`, rounded to the millisecond) and the UTC
//! date and time (to the nanosecond). Where the receiver marks the UTC date and time valid and
//! resolved, an epoch's time is that (leap seconds by hifitime, through the `rinex` crate);
//! elsewhere it is the time of week in the week of the nearest such epoch, carried by the time
//! of week (a week rollover seen as the time of week falling back by more than half a week).

use crate::error::{Error, Result};
use crate::memory::open_bounded;
use std::io::Read;

/// The NAV-PVT solutions of a log, one row per message in file order (SI units).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PvtTable {
    /// GPS seconds since the GPS epoch.
    pub t: Vec<f64>,
    /// Latitude, longitude (deg), height above the ellipsoid and above mean sea level (m).
    pub llh: Vec<[f64; 4]>,
    /// Horizontal and vertical accuracy estimates (m) and the speed accuracy estimate (m/s).
    pub acc: Vec<[f64; 3]>,
    /// Velocity north, east, down (m/s).
    pub vel_ned: Vec<[f64; 3]>,
    /// Satellites used, fix type (0 none, 1 dead reckoning only, 2 2-D, 3 3-D, 4 GNSS + dead
    /// reckoning, 5 time only), the fix flags (bit 0 gnssFixOK, 1 diffSoln, 6–7 carrSoln).
    pub status: Vec<[u8; 3]>,
    /// UBX packets with a bad checksum or length, skipped.
    pub corrupt: usize,
}

const WEEK: f64 = 604_800.0;

/// GPS seconds of a UTC calendar time (leap seconds applied); None if the fields are not a
/// date.
fn gps_of_utc(y: u16, mo: u8, d: u8, h: u8, mi: u8, s: u8, nanos: i32) -> Option<f64> {
    use rinex::prelude::{Epoch, TimeScale};
    let e = Epoch::maybe_from_gregorian(i32::from(y), mo, d, h, mi, s.min(59), 0, TimeScale::UTC)
        .ok()?;
    Some(e.to_gpst_seconds() + f64::from(s.saturating_sub(59)) + f64::from(nanos) * 1e-9)
}

/// Read every NAV-PVT message of the UBX log at `path` (plain or gzip). Errors: the file
/// cannot be read, it holds no UBX packet (not a u-blox log) or no NAV-PVT message (the
/// receiver was not set to output it), or no message has a valid UTC date (no GPS week).
pub fn read_ubx_pvt(path: &str) -> Result<PvtTable> {
    use ublox::proto23::{PacketRef, Proto23};
    use ublox::{ParserBuilder, UbxPacket};
    let mut reader = open_bounded(path)?;
    let mut parser = ParserBuilder::new()
        .with_protocol::<Proto23>()
        .with_vec_buffer();
    let mut out = PvtTable::default();
    let (mut packets, mut itow, mut week_of, mut precise) =
        (0usize, Vec::new(), Vec::new(), Vec::new());
    let mut chunk = vec![0u8; 1 << 16];
    loop {
        let n = reader
            .read(&mut chunk)
            .map_err(|e| crate::memory::read_error(&e, |e| Error::Io(format!("{path}: {e}"))))?;
        if n == 0 {
            break;
        }
        let mut it = parser.consume_ubx(&chunk[..n]);
        while let Some(p) = it.next() {
            let p = match p {
                Ok(p) => p,
                Err(_) => {
                    out.corrupt += 1;
                    continue;
                }
            };
            packets += 1;
            let UbxPacket::Proto23(PacketRef::NavPvt(v)) = p else {
                continue;
            };
            let valid = v.valid_raw();
            // validDate, validTime and fullyResolved: the UTC time to the nanosecond.
            let utc = if valid & 0x07 == 0x07 {
                gps_of_utc(
                    v.year(),
                    v.month(),
                    v.day(),
                    v.hour(),
                    v.min(),
                    v.sec(),
                    v.nanosec(),
                )
            } else {
                None
            };
            itow.push(f64::from(v.itow()) * 1e-3);
            week_of.push(utc.map(|g| ((g - f64::from(v.itow()) * 1e-3) / WEEK).round()));
            precise.push(utc);
            out.llh.push([
                v.latitude(),
                v.longitude(),
                v.height_above_ellipsoid(),
                v.height_msl(),
            ]);
            out.acc.push([
                v.horizontal_accuracy(),
                v.vertical_accuracy(),
                v.speed_accuracy(),
            ]);
            out.vel_ned
                .push([v.vel_north(), v.vel_east(), v.vel_down()]);
            out.status
                .push([v.num_satellites(), v.fix_type_raw(), v.flags_raw()]);
        }
    }
    if packets == 0 {
        return Err(Error::Format(format!(
            "{path}: no UBX packet (sync bytes 0xB5 0x62 with a valid checksum): not a u-blox binary log"
        )));
    }
    if itow.is_empty() {
        return Err(Error::Format(format!(
            "{path}: {packets} UBX packets but no NAV-PVT (class 0x01, id 0x07): set the receiver to output UBX-NAV-PVT, or give its solution in another format (NMEA, RTKLIB .pos)"
        )));
    }
    let from_tow = resolve_weeks(&itow, &week_of).ok_or_else(|| {
        Error::Format(format!(
            "{path}: no NAV-PVT message has a valid, resolved UTC date and time, so the GPS week is unknown"
        ))
    })?;
    // The UTC time to the nanosecond where the receiver resolved it (iTOW is rounded to the
    // millisecond), else the time of week in its week.
    out.t = precise
        .iter()
        .zip(from_tow)
        .map(|(p, t)| p.unwrap_or(t))
        .collect();
    Ok(out)
}

/// GPS seconds from times of week `tow` (s) and the weeks known at some of them: each epoch
/// takes the week of the nearest earlier epoch with one (or, before the first, the first),
/// stepped at every rollover of the time of week between them. None when no week is known.
fn resolve_weeks(tow: &[f64], week: &[Option<f64>]) -> Option<Vec<f64>> {
    let first = week.iter().position(Option::is_some)?;
    let mut t = vec![f64::NAN; tow.len()];
    let mut w = week[first]?;
    for k in first..tow.len() {
        if let Some(known) = week[k] {
            w = known;
        } else if k > first && tow[k] < tow[k - 1] - 0.5 * WEEK {
            w += 1.0;
        }
        t[k] = w * WEEK + tow[k];
    }
    let mut w = week[first]?;
    for k in (0..first).rev() {
        if tow[k] > tow[k + 1] + 0.5 * WEEK {
            w -= 1.0;
        }
        t[k] = w * WEEK + tow[k];
    }
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weeks_are_carried_across_epochs_without_a_date_and_rollovers() {
        let tow = [604_799.0, 0.0, 1.0, 2.0];
        let t = resolve_weeks(&tow, &[None, None, Some(2381.0), None]).unwrap();
        assert_eq!(
            t,
            vec![
                2380.0 * WEEK + 604_799.0,
                2381.0 * WEEK,
                2381.0 * WEEK + 1.0,
                2381.0 * WEEK + 2.0
            ]
        );
        let t = resolve_weeks(&[604_799.5, 0.5], &[Some(10.0), None]).unwrap();
        assert_eq!(t, vec![10.0 * WEEK + 604_799.5, 11.0 * WEEK + 0.5]);
        assert!(resolve_weeks(&[1.0], &[None]).is_none());
    }

    #[test]
    fn utc_dates_take_the_leap_seconds() {
        // 2017-01-01 00:00:00 UTC is 18 s after 00:00:00 GPST that day.
        use rinex::prelude::{Epoch, TimeScale};
        let g = gps_of_utc(2017, 1, 1, 0, 0, 0, 0).unwrap();
        let day = Epoch::maybe_from_gregorian(2017, 1, 1, 0, 0, 0, 0, TimeScale::GPST)
            .unwrap()
            .to_gpst_seconds();
        assert_eq!(g - day, 18.0);
        assert!(gps_of_utc(2017, 13, 1, 0, 0, 0, 0).is_none());
    }

    #[test]
    fn files_that_are_not_ubx_or_have_no_pvt_are_named() {
        let dir = std::env::temp_dir().join(format!("navfdi_ubx_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = dir.join("a.ubx");
        std::fs::write(&text, b"$GPGGA,not,ubx\n").unwrap();
        let e = read_ubx_pvt(text.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a u-blox binary log"), "{e}");
        // One valid UBX-ACK-ACK packet (class 0x05 id 0x01, payload 06 01).
        let mut ack = vec![0xB5, 0x62, 0x05, 0x01, 0x02, 0x00, 0x06, 0x01];
        let (mut a, mut b) = (0u8, 0u8);
        for &x in &ack[2..] {
            a = a.wrapping_add(x);
            b = b.wrapping_add(a);
        }
        ack.extend([a, b]);
        let f = dir.join("b.ubx");
        std::fs::write(&f, &ack).unwrap();
        let e = read_ubx_pvt(f.to_str().unwrap()).unwrap_err().to_string();
        assert!(e.contains("1 UBX packets but no NAV-PVT"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
