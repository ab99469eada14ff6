//! C `printf` number formatting (`%g`, `%e`, `%f`, `%d`, `%s` with width and precision): LIGGGHTS
//! writes every output file with these, and post-processing scripts parse them, so both engines
//! must print numbers the same way.

/// One conversion of a format string.
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    pub left: bool,
    pub plus: bool,
    pub zero: bool,
    pub width: usize,
    pub prec: Option<usize>,
    pub conv: char,
}

/// A parsed format string: literal text and conversions, in order.
#[derive(Debug, Clone, PartialEq)]
pub enum Piece {
    Lit(String),
    Conv(Spec),
}

/// Parses a C format string; only numeric conversions and `%s`, `%%` are accepted.
pub fn parse(fmt: &str) -> Result<Vec<Piece>, String> {
    let mut out = Vec::new();
    let mut lit = String::new();
    let mut it = fmt.chars().peekable();
    while let Some(c) = it.next() {
        if c != '%' {
            lit.push(c);
            continue;
        }
        if it.peek() == Some(&'%') {
            it.next();
            lit.push('%');
            continue;
        }
        if !lit.is_empty() {
            out.push(Piece::Lit(std::mem::take(&mut lit)));
        }
        let mut s = Spec { left: false, plus: false, zero: false, width: 0, prec: None, conv: 'g' };
        while let Some(&f) = it.peek() {
            match f {
                '-' => s.left = true,
                '+' => s.plus = true,
                '0' => s.zero = true,
                ' ' | '#' => {}
                _ => break,
            }
            it.next();
        }
        while let Some(&d) = it.peek().filter(|d| d.is_ascii_digit()) {
            s.width = s.width * 10 + (d as usize - '0' as usize);
            it.next();
        }
        if it.peek() == Some(&'.') {
            it.next();
            let mut p = 0;
            while let Some(&d) = it.peek().filter(|d| d.is_ascii_digit()) {
                p = p * 10 + (d as usize - '0' as usize);
                it.next();
            }
            s.prec = Some(p);
        }
        // Length modifiers (l, ll, h) do not matter here.
        while matches!(it.peek(), Some('l') | Some('h') | Some('L')) {
            it.next();
        }
        match it.next() {
            Some(c @ ('g' | 'G' | 'e' | 'E' | 'f' | 'F' | 'd' | 'i' | 'u' | 's')) => s.conv = c,
            other => return Err(format!("unsupported conversion in format \"{fmt}\": {other:?}")),
        }
        out.push(Piece::Conv(s));
    }
    if !lit.is_empty() {
        out.push(Piece::Lit(lit));
    }
    Ok(out)
}

fn pad(s: String, spec: &Spec) -> String {
    if s.len() >= spec.width {
        return s;
    }
    let fill = spec.width - s.len();
    if spec.left {
        format!("{s}{}", " ".repeat(fill))
    } else if spec.zero && spec.conv != 's' {
        let (sign, rest) =
            if s.starts_with('-') || s.starts_with('+') { s.split_at(1) } else { ("", &s[..]) };
        format!("{sign}{}{rest}", "0".repeat(fill))
    } else {
        format!("{}{s}", " ".repeat(fill))
    }
}

/// `%e` body: mantissa with `prec` decimals and a signed exponent of at least two digits.
fn exp_body(x: f64, prec: usize, upper: bool) -> String {
    let s = format!("{:.*e}", prec, x);
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    let e: i32 = e.parse().unwrap_or(0);
    let sign = if e < 0 { '-' } else { '+' };
    let t = format!("{m}e{sign}{:02}", e.abs());
    if upper {
        t.to_uppercase()
    } else {
        t
    }
}

fn strip_zeros(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

/// `%.{prec}g` without padding.
pub fn g(x: f64, prec: usize) -> String {
    let p = prec.max(1);
    if x == 0.0 {
        return if x.is_sign_negative() { "-0".into() } else { "0".into() };
    }
    if !x.is_finite() {
        return if x.is_nan() {
            "nan".into()
        } else if x > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        };
    }
    let s = format!("{:.*e}", p - 1, x);
    let e: i32 = s.split_once('e').map(|(_, e)| e.parse().unwrap_or(0)).unwrap_or(0);
    if e < -4 || e >= p as i32 {
        let body = exp_body(x, p - 1, false);
        let (m, ex) = body.split_once('e').unwrap_or((&body, ""));
        format!("{}e{ex}", strip_zeros(m))
    } else {
        let decimals = (p as i32 - 1 - e).max(0) as usize;
        strip_zeros(&format!("{:.*}", decimals, x))
    }
}

/// Formats one value with one conversion.
pub fn number(spec: &Spec, x: f64) -> String {
    let body = match spec.conv {
        'g' | 'G' => {
            let s = g(x, spec.prec.unwrap_or(6));
            if spec.conv == 'G' {
                s.to_uppercase()
            } else {
                s
            }
        }
        'e' | 'E' => exp_body(x, spec.prec.unwrap_or(6), spec.conv == 'E'),
        'f' | 'F' => format!("{:.*}", spec.prec.unwrap_or(6), x),
        'd' | 'i' | 'u' => format!("{}", x.round() as i64),
        _ => g(x, 6),
    };
    let body = if spec.plus && !body.starts_with('-') { format!("+{body}") } else { body };
    pad(body, spec)
}

/// Formats a string with a `%s` conversion (or any conversion: width only).
pub fn text(spec: &Spec, s: &str) -> String {
    pad(s.to_string(), spec)
}

/// Shorthand: `%{width}.{prec}g`.
pub fn gw(x: f64, width: usize, prec: usize) -> String {
    let spec = Spec { left: false, plus: false, zero: false, width, prec: Some(prec), conv: 'g' };
    number(&spec, x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_c_printf() {
        assert_eq!(g(-0.1004215, 15), "-0.1004215");
        assert_eq!(g(0.00776359, 6), "0.00776359");
        assert_eq!(g(-7.00163e-06, 6), "-7.00163e-06");
        assert_eq!(g(100.0, 6), "100");
        assert_eq!(g(1e6, 6), "1e+06");
        assert_eq!(g(123456.7, 6), "123457");
        assert_eq!(g(0.0001, 6), "0.0001");
        assert_eq!(g(0.00001, 6), "1e-05");
        assert_eq!(gw(4.5519325e-10, 14, 8), " 4.5519325e-10");
        assert_eq!(gw(0.013644751, 14, 8), "   0.013644751");
        let p = parse("%8d %14.8g|%-5s%%").unwrap();
        assert_eq!(p.len(), 6);
    }
}
