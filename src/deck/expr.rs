//! Equal-style variable formulas (LAMMPS `variable NAME equal …`): numbers, `+ - * / ^`,
//! comparisons and logic, parentheses, math functions, and names (thermo keywords, `v_`, `c_`,
//! `f_`, per-atom references such as `x[3]`) that the caller resolves.

/// Resolves a name (`step`, `v_x`, `c_1`, `f_piston[3]`, `x[12]`, …) to a number.
pub trait Resolve {
    fn resolve(&self, name: &str) -> Result<f64, String>;
}

/// Evaluates a formula.
pub fn eval(src: &str, r: &dyn Resolve) -> Result<f64, String> {
    let mut p = Parser { s: src.as_bytes(), i: 0, r };
    let v = p.or()?;
    p.ws();
    if p.i != p.s.len() {
        return Err(format!("cannot parse formula \"{src}\" at \"{}\"", &src[p.i..]));
    }
    Ok(v)
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
    r: &'a dyn Resolve,
}

impl Parser<'_> {
    fn ws(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }

    fn eat(&mut self, t: &str) -> bool {
        self.ws();
        if self.s[self.i..].starts_with(t.as_bytes()) {
            self.i += t.len();
            true
        } else {
            false
        }
    }

    fn or(&mut self) -> Result<f64, String> {
        let mut a = self.and()?;
        while self.eat("||") {
            let b = self.and()?;
            a = f64::from(a != 0.0 || b != 0.0);
        }
        Ok(a)
    }

    fn and(&mut self) -> Result<f64, String> {
        let mut a = self.eq()?;
        while self.eat("&&") {
            let b = self.eq()?;
            a = f64::from(a != 0.0 && b != 0.0);
        }
        Ok(a)
    }

    fn eq(&mut self) -> Result<f64, String> {
        let mut a = self.cmp()?;
        loop {
            if self.eat("==") {
                let b = self.cmp()?;
                a = f64::from(a == b);
            } else if self.eat("!=") {
                let b = self.cmp()?;
                a = f64::from(a != b);
            } else {
                return Ok(a);
            }
        }
    }

    fn cmp(&mut self) -> Result<f64, String> {
        let mut a = self.add()?;
        loop {
            if self.eat("<=") {
                let b = self.add()?;
                a = f64::from(a <= b);
            } else if self.eat(">=") {
                let b = self.add()?;
                a = f64::from(a >= b);
            } else if self.eat("<") {
                let b = self.add()?;
                a = f64::from(a < b);
            } else if self.eat(">") {
                let b = self.add()?;
                a = f64::from(a > b);
            } else {
                return Ok(a);
            }
        }
    }

    fn add(&mut self) -> Result<f64, String> {
        let mut a = self.mul()?;
        loop {
            if self.eat("+") {
                a += self.mul()?;
            } else if self.eat("-") {
                a -= self.mul()?;
            } else {
                return Ok(a);
            }
        }
    }

    fn mul(&mut self) -> Result<f64, String> {
        let mut a = self.unary()?;
        loop {
            if self.eat("*") {
                a *= self.unary()?;
            } else if self.eat("/") {
                let b = self.unary()?;
                if b == 0.0 {
                    return Err("division by zero in formula".into());
                }
                a /= b;
            } else if self.eat("%") {
                let b = self.unary()?;
                if b == 0.0 {
                    return Err("modulo by zero in formula".into());
                }
                // LAMMPS: fmod (the sign follows the dividend).
                a %= b;
            } else {
                return Ok(a);
            }
        }
    }

    fn unary(&mut self) -> Result<f64, String> {
        if self.eat("-") {
            return Ok(-self.unary()?);
        }
        if self.eat("!") {
            return Ok(f64::from(self.unary()? == 0.0));
        }
        if self.eat("+") {
            return self.unary();
        }
        self.pow()
    }

    fn pow(&mut self) -> Result<f64, String> {
        let a = self.atom()?;
        if self.eat("^") {
            let b = self.unary()?;
            return Ok(a.powf(b));
        }
        Ok(a)
    }

    fn atom(&mut self) -> Result<f64, String> {
        self.ws();
        if self.eat("(") {
            let v = self.or()?;
            if !self.eat(")") {
                return Err("missing ')' in formula".into());
            }
            return Ok(v);
        }
        let start = self.i;
        let c = *self.s.get(self.i).ok_or("formula ends unexpectedly")?;
        if c.is_ascii_digit() || c == b'.' {
            while self.i < self.s.len() && (self.s[self.i].is_ascii_digit() || self.s[self.i] == b'.') {
                self.i += 1;
            }
            if self.i < self.s.len() && (self.s[self.i] == b'e' || self.s[self.i] == b'E') {
                let save = self.i;
                self.i += 1;
                if self.i < self.s.len() && (self.s[self.i] == b'+' || self.s[self.i] == b'-') {
                    self.i += 1;
                }
                if self.i < self.s.len() && self.s[self.i].is_ascii_digit() {
                    while self.i < self.s.len() && self.s[self.i].is_ascii_digit() {
                        self.i += 1;
                    }
                } else {
                    self.i = save;
                }
            }
            let t = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
            return t.parse::<f64>().map_err(|_| format!("bad number \"{t}\" in formula"));
        }
        if c.is_ascii_alphabetic() || c == b'_' {
            while self.i < self.s.len() && (self.s[self.i].is_ascii_alphanumeric() || self.s[self.i] == b'_')
            {
                self.i += 1;
            }
            let name = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("").to_string();
            // Function call.
            if self.eat("(") {
                let mut args = vec![self.or()?];
                while self.eat(",") {
                    args.push(self.or()?);
                }
                if !self.eat(")") {
                    return Err(format!("missing ')' after arguments of {name}()"));
                }
                return call(&name, &args);
            }
            // Bracketed index: c_ID[2], f_ID[3], x[5].
            let mut full = name;
            if self.i < self.s.len() && self.s[self.i] == b'[' {
                let b = self.i;
                while self.i < self.s.len() && self.s[self.i] != b']' {
                    self.i += 1;
                }
                if self.i == self.s.len() {
                    return Err("missing ']' in formula".into());
                }
                self.i += 1;
                full.push_str(std::str::from_utf8(&self.s[b..self.i]).unwrap_or(""));
            }
            if full == "PI" {
                return Ok(std::f64::consts::PI);
            }
            return self.r.resolve(&full);
        }
        Err(format!("unexpected character '{}' in formula", c as char))
    }
}

fn call(name: &str, a: &[f64]) -> Result<f64, String> {
    let one = |f: fn(f64) -> f64| -> Result<f64, String> {
        if a.len() != 1 {
            return Err(format!("{name}() takes one argument"));
        }
        Ok(f(a[0]))
    };
    match name {
        "sqrt" => {
            if a.first().is_some_and(|v| *v < 0.0) {
                return Err("sqrt() of a negative number in formula".into());
            }
            one(f64::sqrt)
        }
        "exp" => one(f64::exp),
        "ln" => one(f64::ln),
        "log" => one(f64::log10),
        "abs" => one(f64::abs),
        "sin" => one(f64::sin),
        "cos" => one(f64::cos),
        "tan" => one(f64::tan),
        "asin" => one(f64::asin),
        "acos" => one(f64::acos),
        "atan" => one(f64::atan),
        "ceil" => one(f64::ceil),
        "floor" => one(f64::floor),
        "round" => one(f64::round),
        "atan2" if a.len() == 2 => Ok(a[0].atan2(a[1])),
        "min" if a.len() == 2 => Ok(a[0].min(a[1])),
        "max" if a.len() == 2 => Ok(a[0].max(a[1])),
        _ => Err(format!("unsupported function {name}() in formula")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct R;
    impl Resolve for R {
        fn resolve(&self, name: &str) -> Result<f64, String> {
            match name {
                "v_a" => Ok(2.0),
                "f_m[3]" => Ok(5.0),
                _ => Err(format!("unknown {name}")),
            }
        }
    }

    #[test]
    fn arithmetic() {
        assert_eq!(eval("-0.03012645/(30000*1e-05)", &R).unwrap(), -0.03012645 / (30000.0 * 1e-05));
        assert_eq!(eval("-1*-0.1004215", &R).unwrap(), 0.1004215);
        assert_eq!(eval("2^3*v_a + f_m[3]", &R).unwrap(), 21.0);
        assert_eq!(eval("sqrt(4) > 1 && 1", &R).unwrap(), 1.0);
        assert!(eval("1/0", &R).is_err());
        assert_eq!(eval("7%3 + (-7)%3", &R).unwrap(), 0.0);
        assert!(eval("1%0", &R).is_err());
        assert!(eval("v_b", &R).is_err());
    }
}
