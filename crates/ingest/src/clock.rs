//! Clock times of day written as text (`12:00:01.5`, `00:01:02,25`, `2024-05-01 12:00:01.5`,
//! `01.05.2024T12:00:01`, `8:21:18 PM`): a logger's time stamp, which a reader keeps as a text
//! column unless it is read as seconds.

/// Seconds since midnight of a clock time `h:mm:ss[.fff]` (a decimal point or comma; a
/// 12-hour `AM`/`PM` after it), or of `mm:ss.fff` (two parts only with a fraction of a second,
/// which `h:mm` never has), optionally after a date of digits and `-./` separated by a space
/// or `T`. None for anything else.
pub fn clock_seconds(text: &str) -> Option<f64> {
    let mut t = text.trim();
    let mut pm = None;
    for (suffix, is_pm) in [("AM", false), ("PM", true), ("am", false), ("pm", true)] {
        if let Some(rest) = t.strip_suffix(suffix) {
            t = rest.trim_end();
            pm = Some(is_pm);
            break;
        }
    }
    if let Some(k) = t.rfind([' ', 'T']) {
        let (date, rest) = (&t[..k], &t[k + 1..]);
        let date = date.trim();
        if date.is_empty()
            || !date.chars().any(|c| c.is_ascii_digit())
            || !date
                .chars()
                .all(|c| c.is_ascii_digit() || "-./".contains(c))
        {
            return None;
        }
        t = rest;
    }
    let parts: Vec<&str> = t.split(':').collect();
    let whole = |s: &str, max: u32| -> Option<f64> {
        (!s.is_empty() && s.len() <= 2 && s.bytes().all(|b| b.is_ascii_digit()))
            .then(|| s.parse::<u32>().ok())
            .flatten()
            .filter(|&v| v < max)
            .map(f64::from)
    };
    let seconds = |s: &str| -> Option<f64> {
        let (int, frac) = match s.find(['.', ',']) {
            Some(i) => (&s[..i], Some(&s[i + 1..])),
            None => (s, None),
        };
        let mut v = whole(int, 60)?;
        if let Some(f) = frac {
            if f.is_empty() || !f.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            v += format!("0.{f}").parse::<f64>().ok()?;
        }
        Some(v)
    };
    let (h, m, s) = match parts.as_slice() {
        [h, m, s] => (
            whole(h, if pm.is_some() { 13 } else { 100 })?,
            whole(m, 60)?,
            seconds(s)?,
        ),
        [m, s] if pm.is_none() && s.contains(['.', ',']) => (0.0, whole(m, 60)?, seconds(s)?),
        _ => return None,
    };
    let h = match pm {
        Some(true) if h < 12.0 => h + 12.0,
        Some(false) if h == 12.0 => 0.0,
        _ => h,
    };
    Some(3600.0 * h + 60.0 * m + s)
}

/// A text column of clock times as seconds from its first (NaN for an empty cell), a day added
/// where the clock falls back by more than half a day (past midnight). None unless every
/// non-empty cell is a clock time, at least two are, and the times rise on at least 99 % of the
/// steps between filled cells (a stamp coarser than the sampling repeats itself and is no time
/// base).
pub fn clock_column(texts: &[String]) -> Option<Vec<f64>> {
    let mut out = Vec::with_capacity(texts.len());
    let (mut day, mut prev, mut first) = (0.0, None::<f64>, None::<f64>);
    let (mut steps, mut rising) = (0usize, 0usize);
    for t in texts {
        if t.trim().is_empty() {
            out.push(f64::NAN);
            continue;
        }
        let mut v = clock_seconds(t)? + day;
        if let Some(p) = prev {
            if v < p - 43_200.0 {
                day += 86_400.0;
                v += 86_400.0;
            }
            steps += 1;
            rising += usize::from(v > p);
        }
        prev = Some(v);
        let f = *first.get_or_insert(v);
        out.push(v - f);
    }
    (steps >= 1 && rising as f64 >= 0.99 * steps as f64).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clock_times_in_the_forms_loggers_write() {
        for (text, s) in [
            ("12:00:01.5", 43_201.5),
            ("00:01:02,25", 62.25),
            ("2024-05-01 12:00:01.5", 43_201.5),
            ("01.05.2024T08:21:18", 30_078.0),
            ("4/27/2019 8:21:18 PM", 73_278.0),
            ("12:05:00 AM", 300.0),
            ("01:02.5", 62.5),
            ("99:00:00", 356_400.0),
        ] {
            let v = clock_seconds(text).unwrap_or_else(|| panic!("{text}"));
            assert!((v - s).abs() < 1e-9, "{text}: {v}");
        }
        for text in [
            "12:30",
            "1.5",
            "12:61:00",
            "abc 12:00:00",
            "12:00:00x",
            "",
            "3:4:5:6",
            "13:00:00 PM",
        ] {
            assert!(clock_seconds(text).is_none(), "{text}");
        }
    }

    #[test]
    fn a_column_of_clock_times_is_seconds_from_its_first_row() {
        let col = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let c = clock_column(&col(&["23:59:59.5", "", "23:59:59.9", "00:00:00.3"])).unwrap();
        assert_eq!(c[0], 0.0);
        assert!(c[1].is_nan());
        assert!(
            (c[2] - 0.4).abs() < 1e-9 && (c[3] - 0.8).abs() < 1e-9,
            "{c:?}"
        );
        // Whole seconds at a faster sampling repeat themselves: no time base.
        assert!(clock_column(&col(&["12:00:00", "12:00:00", "12:00:01", "12:00:01"])).is_none());
        // A label that is not a clock time.
        assert!(clock_column(&col(&["12:00:00", "hold"])).is_none());
        assert!(clock_column(&col(&["12:00:00"])).is_none());
    }
}
