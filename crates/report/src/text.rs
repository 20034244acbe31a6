//! Text helpers for the report: HTML/XML escaping, stable number formatting and SI-prefix
//! scaling of axis labels.
//!
//! Everything here is a pure string function, so identical input always gives identical bytes.
//! It does not draw anything and knows nothing about plots or HTML layout.

/// Escapes a string for use as HTML/XML text or inside a double- or single-quoted attribute:
/// `&`, `<`, `>`, `"` and `'` become entities; control characters other than tab, line feed
/// and carriage return (not allowed in XML 1.0) are dropped.
pub fn escape_html(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + s.len() / 8);
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            '\t' | '\n' | '\r' => out.push(c),
            c if c.is_control() => {}
            c => out.push(c),
        }
    }
    out
}

/// `s` in at most `max` characters: whole when it fits, else its start and end around a "…"
/// (a file name's end tells the files of a folder apart as often as its start).
pub fn shorten_middle(s: &str, max: usize) -> String {
    let n = s.chars().count();
    if n <= max || max < 3 {
        return s.to_string();
    }
    let keep = max - 1;
    let head = keep.div_ceil(2);
    let tail = keep - head;
    let start: String = s.chars().take(head).collect();
    let end: String = s.chars().skip(n - tail).collect();
    format!("{start}…{end}")
}

/// Drops the characters that XML 1.0 forbids (control characters other than tab, line feed and
/// carriage return) without escaping anything else. plotters escapes markup in SVG text but
/// passes these through, and a single one makes the whole SVG ill-formed.
pub fn strip_xml_forbidden(s: &str) -> String {
    s.chars()
        .filter(|&c| !c.is_control() || matches!(c, '\t' | '\n' | '\r'))
        .collect()
}

/// Turns an input-derived string into a safe HTML `id` fragment: ASCII letters, digits, `-` and
/// `_` are kept (lower-cased), every other run of characters becomes one `-`. Never empty (falls
/// back to `section`) and always starts with a letter (prefixed with `s-` otherwise).
pub fn slug(s: &str) -> String {
    let mut out = String::new();
    let mut pending_dash = false;
    for c in s.chars() {
        if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
            if pending_dash && !out.is_empty() {
                out.push('-');
            }
            pending_dash = false;
            out.push(c.to_ascii_lowercase());
        } else {
            pending_dash = true;
        }
    }
    if out.is_empty() {
        return "section".to_string();
    }
    if !out.starts_with(|c: char| c.is_ascii_alphabetic()) {
        out.insert_str(0, "s-");
    }
    out
}

/// Formats a number with `sig` significant digits in plain decimal notation where that stays
/// short (0.01 ≤ |v| < 10 000), else as `m·10ⁿ` with Unicode superscripts, as the chapter's tables
/// write them (`7.96·10⁴`). Stable: the same value always gives the same string; `-0` prints as
/// `0`; NaN and infinities print as `–` (an en dash: "not available").
pub fn fmt_num(v: f64, sig: usize) -> String {
    if !v.is_finite() {
        return "\u{2013}".to_string();
    }
    let sig = sig.clamp(1, 15);
    if v == 0.0 {
        return "0".to_string();
    }
    let (mant, exp) = mant_exp(v, sig);
    if (-2..4).contains(&exp) {
        let decimals = (sig as i32 - 1 - exp).max(0) as usize;
        let s = format!("{:.*}", decimals, mant * 10f64.powi(exp));
        if s.starts_with('-') && s.trim_start_matches(['-', '0', '.']).is_empty() {
            return s.trim_start_matches('-').to_string();
        }
        s
    } else {
        format!(
            "{:.*}\u{b7}10{}",
            sig - 1,
            mant,
            superscript(&exp.to_string())
        )
    }
}

/// Mantissa rounded to `sig` significant digits and decimal exponent of a finite non-zero value.
fn mant_exp(v: f64, sig: usize) -> (f64, i32) {
    let exp = v.abs().log10().floor() as i32;
    let factor = 10f64.powi(sig as i32 - 1);
    let m = (v / 10f64.powi(exp) * factor).round() / factor;
    // Rounding can carry into the next decade (9.996 → 10.0).
    if m.abs() >= 10.0 {
        (m / 10.0, exp + 1)
    } else {
        (m, exp)
    }
}

/// Formats `mean ± sd` with the mean to `sig` significant digits and the sd to the same
/// decimal place: `1.40 ± 0.07`, or with a shared power of ten `(7.96 ± 0.12)·10⁴` where
/// [`fmt_num`] would use one.
pub fn fmt_mean_sd(mean: f64, sd: f64, sig: usize) -> String {
    if !mean.is_finite() || mean == 0.0 || !sd.is_finite() {
        return format!("{} \u{b1} {}", fmt_num(mean, sig), fmt_num(sd, 2));
    }
    let sig = sig.clamp(1, 15);
    let (_, exp) = mant_exp(mean, sig);
    let fixed = |x: f64, d: usize| {
        let s = format!("{:.*}", d, x);
        if s.starts_with('-') && s.trim_start_matches(['-', '0', '.']).is_empty() {
            s[1..].to_string()
        } else {
            s
        }
    };
    // A nonzero sd that the mean's decimals would round to 0 gets the decimals of its first
    // significant digit, the mean with it (Table 1 read "(1.37 ± 0.00)·10⁻³" for a CoV of 0.1 %).
    let at_least = |d: usize, sd: f64| {
        if sd > 0.0 && sd.is_finite() {
            d.max((-sd.log10().floor()).clamp(0.0, 9.0) as usize)
        } else {
            d
        }
    };
    if (-2..4).contains(&exp) {
        let d = at_least((sig as i32 - 1 - exp).max(0) as usize, sd.abs());
        format!("{} \u{b1} {}", fixed(mean, d), fixed(sd.abs(), d))
    } else {
        let scale = 10f64.powi(-exp);
        let d = at_least(sig - 1, sd.abs() * scale);
        format!(
            "({} \u{b1} {})\u{b7}10{}",
            fixed(mean * scale, d),
            fixed(sd.abs() * scale, d),
            superscript(&exp.to_string())
        )
    }
}

/// Formats a modulus given in Pa as MPa the way the chapter's Table 1 does: one decimal below
/// 10 000 MPa (`1003.7`, `454.4`), none above (`12900`).
pub fn fmt_mpa(pa: f64) -> String {
    if !pa.is_finite() {
        return "\u{2013}".to_string();
    }
    let mpa = pa / 1e6;
    if mpa.abs() >= 1e4 {
        format!("{:.0}", mpa)
    } else {
        format!("{:.1}", mpa)
    }
}

/// A fraction as a percentage to two significant digits (at least one decimal): 0.0015096 is
/// "0.15 %", 0.0112 "1.1 %". Two numbers that differ read differently where one decimal made a
/// gap of 0.15 % and a floor of 0.11 % "0.2 %" and "0.1 %".
pub fn fmt_percent_2sig(fraction: f64) -> String {
    let p = (fraction * 100.0).abs();
    let decimals = if p > 0.0 && p.is_finite() {
        (1 - p.log10().floor() as i32).clamp(1, 6) as usize
    } else {
        1
    };
    fmt_percent(fraction, decimals)
}

/// Formats a fraction as a percentage with `decimals` decimals (`0.1234` → `12.3 %`).
pub fn fmt_percent(fraction: f64, decimals: usize) -> String {
    if !fraction.is_finite() {
        return "\u{2013}".to_string();
    }
    let s = format!("{:.*}", decimals, fraction * 100.0);
    let s = if s.starts_with('-') && s.trim_start_matches(['-', '0', '.']).is_empty() {
        s.trim_start_matches('-').to_string()
    } else {
        s
    };
    format!("{s}\u{a0}%")
}

/// Converts the digits and sign of an integer string to Unicode superscripts (`-3` → `⁻³`).
pub fn superscript(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '0' => '\u{2070}',
            '1' => '\u{b9}',
            '2' => '\u{b2}',
            '3' => '\u{b3}',
            '4' => '\u{2074}',
            '5' => '\u{2075}',
            '6' => '\u{2076}',
            '7' => '\u{2077}',
            '8' => '\u{2078}',
            '9' => '\u{2079}',
            '-' => '\u{207b}',
            '+' => '\u{207a}',
            other => other,
        })
        .collect()
}

/// The engineering exponent (a multiple of 3) that brings the largest finite |value| into
/// [1, 1000), or 0 when the values already lie in [0.1, 10000) or there are none. Used to keep
/// tick labels short: an elongation of 0.0004 m is plotted as 0.4 mm.
pub fn engineering_exponent(values: impl IntoIterator<Item = f64>) -> i32 {
    let max = values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    if max == 0.0 || (1e-1..1e4).contains(&max) {
        return 0;
    }
    (max.log10().floor() as i32).div_euclid(3) * 3
}

/// A value with the unit an axis over `range` shows it in: the axis `elongation Δl [m]` over
/// 0…40 µm is drawn in µm, so 2.06·10⁻⁵ m reads `20.6 µm` (`sig` significant digits).
pub fn fmt_on_axis(
    v: f64,
    range: impl IntoIterator<Item = f64>,
    label: &str,
    sig: usize,
) -> String {
    let unit_in = |l: &str| match (l.rfind('['), l.ends_with(']')) {
        (Some(i), true) => l[i + 1..l.len() - 1].to_string(),
        _ => String::new(),
    };
    let mut exp = engineering_exponent(range);
    let mut unit = unit_in(&scaled_label(label, exp));
    // A compound unit is scaled by a power of ten on the axis; a number carries that itself.
    if unit.starts_with("10") {
        exp = 0;
        unit = unit_in(label);
    }
    let num = fmt_num(v * 10f64.powi(-exp), sig);
    if unit.is_empty() || unit == "-" {
        num
    } else {
        format!("{num} {unit}")
    }
}

/// Rewrites an axis label `quantity [unit]` for values divided by `10^exp`: simple units get an
/// SI prefix (`[m]` → `[mm]`, `[N]` → `[kN]`), compound ones a power of ten
/// (`[N m]` → `[10⁻³ N m]`); a label without a `[unit]` gets ` [10ⁿ]` appended. `exp = 0` leaves
/// the label unchanged.
pub fn scaled_label(label: &str, exp: i32) -> String {
    if exp == 0 {
        return label.to_string();
    }
    let prefix = match exp {
        -12 => Some("p"),
        -9 => Some("n"),
        -6 => Some("\u{b5}"),
        -3 => Some("m"),
        3 => Some("k"),
        6 => Some("M"),
        9 => Some("G"),
        _ => None,
    };
    let power = format!("10{}", superscript(&exp.to_string()));
    if let (Some(open), true) = (label.rfind('['), label.ends_with(']')) {
        let unit = &label[open + 1..label.len() - 1];
        let simple = matches!(unit, "m" | "N" | "rad" | "s" | "J" | "Pa" | "W");
        let new_unit = match (prefix, simple) {
            (Some(p), true) => format!("{p}{unit}"),
            _ if unit.is_empty() || unit == "-" || unit == "1" => power,
            _ => format!("{power} {unit}"),
        };
        format!("{}[{}]", &label[..open], new_unit)
    } else {
        format!("{label} [{power}]")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shorten_middle_keeps_both_ends_within_the_limit() {
        assert_eq!(shorten_middle("short", 10), "short");
        assert_eq!(shorten_middle("abcdefghij", 10), "abcdefghij");
        let s = shorten_middle(
            "tension__kinematic_hardening__vary126/vary-0.TXT — tension",
            21,
        );
        assert_eq!(s.chars().count(), 21, "{s}");
        assert_eq!(s, "tension__k… — tension");
        assert_eq!(shorten_middle("αβγδεζηθικ", 5), "αβ…ικ");
    }

    #[test]
    fn escape_html_replaces_all_five_markup_characters() {
        assert_eq!(
            escape_html(r#"<script>alert("x & 'y'")</script>"#),
            "&lt;script&gt;alert(&quot;x &amp; &#39;y&#39;&quot;)&lt;/script&gt;"
        );
        // Entities already present are escaped again: input text is text, not markup.
        assert_eq!(escape_html("&amp;"), "&amp;amp;");
        assert_eq!(escape_html("Δl [mm] µ°"), "Δl [mm] µ°");
        assert_eq!(escape_html("a\u{0}b\u{1b}c\nd"), "abc\nd");
    }

    #[test]
    fn strip_xml_forbidden_keeps_text_and_whitespace() {
        assert_eq!(strip_xml_forbidden("a\u{7}b\tc\n"), "ab\tc\n");
    }

    #[test]
    fn slug_is_safe_and_never_empty() {
        assert_eq!(slug("Cable 2.8 / T-01"), "cable-2-8-t-01");
        assert_eq!(slug("<script>"), "script");
        assert_eq!(slug("§§"), "section");
        assert_eq!(slug("01_tension"), "s-01_tension");
    }

    #[test]
    fn fmt_num_matches_chapter_style() {
        assert_eq!(fmt_num(7.96e4, 3), "7.96\u{b7}10\u{2074}");
        assert_eq!(fmt_num(2.02e-3, 3), "2.02\u{b7}10\u{207b}\u{b3}");
        assert_eq!(fmt_num(1003.7, 5), "1003.7");
        assert_eq!(fmt_num(454.4, 4), "454.4");
        assert_eq!(fmt_num(0.18, 2), "0.18");
        assert_eq!(fmt_num(9.996, 3), "10.0");
        assert_eq!(fmt_num(-0.0, 3), "0");
        assert_eq!(fmt_num(-1.5, 2), "-1.5");
        assert_eq!(fmt_num(f64::NAN, 3), "\u{2013}");
        assert_eq!(fmt_num(12900.0, 3), "1.29\u{b7}10\u{2074}");
        assert_eq!(fmt_num(0.0123, 3), "0.0123");
        assert_eq!(fmt_num(0.00123, 3), "1.23\u{b7}10\u{207b}\u{b3}");
        assert_eq!(fmt_num(129000.0, 3), "1.29\u{b7}10\u{2075}");
    }

    #[test]
    fn fmt_mean_sd_shares_decimals_and_exponent() {
        assert_eq!(fmt_mean_sd(1.4, 0.07, 3), "1.40 \u{b1} 0.07");
        // An sd below the mean's last decimal shows its first digit (a CoV of 0.1 %).
        assert_eq!(
            fmt_mean_sd(1.3703e-3, 1.4e-6, 3),
            "(1.370 \u{b1} 0.001)\u{b7}10\u{207b}\u{b3}"
        );
        assert_eq!(fmt_mean_sd(12.5, 0.004, 3), "12.500 \u{b1} 0.004");
        assert_eq!(
            fmt_mean_sd(7.96e4, 1.2e3, 3),
            "(7.96 \u{b1} 0.12)\u{b7}10\u{2074}"
        );
        assert_eq!(
            fmt_mean_sd(2.02e-3, 5e-5, 3),
            "(2.02 \u{b1} 0.05)\u{b7}10\u{207b}\u{b3}"
        );
    }

    #[test]
    fn fmt_mpa_matches_table_1() {
        assert_eq!(fmt_mpa(12900e6), "12900");
        assert_eq!(fmt_mpa(1003.7e6), "1003.7");
        assert_eq!(fmt_mpa(454.4e6), "454.4");
    }

    #[test]
    fn fmt_percent_rounds_and_drops_negative_zero() {
        assert_eq!(fmt_percent(0.1234, 1), "12.3\u{a0}%");
        assert_eq!(fmt_percent(-0.0001, 1), "0.0\u{a0}%");
    }

    #[test]
    fn engineering_exponent_picks_multiples_of_three() {
        assert_eq!(engineering_exponent([0.0, 4e-4, -2e-4]), -6);
        assert_eq!(engineering_exponent([0.0, 2e-3]), -3);
        assert_eq!(engineering_exponent([0.0, 100.0]), 0);
        assert_eq!(engineering_exponent([0.0, 0.84]), 0);
        assert_eq!(engineering_exponent([0.0, 0.058]), -3);
        assert_eq!(engineering_exponent([7.96e4]), 3);
        assert_eq!(engineering_exponent([f64::NAN]), 0);
        assert_eq!(engineering_exponent([]), 0);
    }

    #[test]
    fn values_read_in_their_axis_units() {
        let l = "elongation \u{394}l [m]";
        assert_eq!(fmt_on_axis(2.06e-5, [0.0, 4e-5], l, 3), "20.6 \u{b5}m");
        assert_eq!(fmt_on_axis(2.06e-3, [0.0, 4e-3], l, 3), "2.06 mm");
        assert_eq!(fmt_on_axis(52.0, [0.0, 100.0], "force F [N]", 3), "52.0 N");
        assert_eq!(
            fmt_on_axis(3.2e-3, [0.0, 5e-3], "moment [N m]", 2),
            "3.2\u{b7}10\u{207b}\u{b3} N m"
        );
    }

    #[test]
    fn scaled_label_prefixes_simple_units_and_powers_compound_ones() {
        assert_eq!(
            scaled_label("elongation \u{394}l [m]", -3),
            "elongation \u{394}l [mm]"
        );
        assert_eq!(scaled_label("force F [N]", 3), "force F [kN]");
        assert_eq!(
            scaled_label("moment M [N m]", -3),
            "moment M [10\u{207b}\u{b3} N m]"
        );
        assert_eq!(scaled_label("strain", -3), "strain [10\u{207b}\u{b3}]");
        assert_eq!(scaled_label("force F [N]", 0), "force F [N]");
    }
}
