//! A small evaluator for the values Sinumerik programs assign and use
//! (`Z=_Z_HOME`, `_F=2*_F_CUT`, `(A+B)/2`): numbers, variables, + − × ÷, parentheses.

use std::collections::BTreeMap;

/// Evaluates `text` with the given variables (names upper-case), nested at
/// most as deep as the default `expression-depth` limit.
pub fn eval(text: &str, vars: &BTreeMap<String, f64>) -> Result<f64, String> {
    eval_within(text, vars, crate::Limits::default().expression_depth)
}

/// [`eval`] with parentheses and signs nested at most `max_depth` deep: the
/// evaluator recurses once per level, and a 12 KB line of `-` would
/// otherwise overflow the reader's stack.
pub fn eval_within(
    text: &str,
    vars: &BTreeMap<String, f64>,
    max_depth: u64,
) -> Result<f64, String> {
    let mut p = P {
        b: text.as_bytes(),
        i: 0,
        vars,
        depth: 0,
        max_depth,
    };
    let v = p.sum()?;
    p.ws();
    if p.i != p.b.len() {
        return Err(format!("unexpected `{}`", &text[p.i..]));
    }
    if !v.is_finite() {
        return Err("value is not finite".into());
    }
    Ok(v)
}

struct P<'a> {
    b: &'a [u8],
    i: usize,
    vars: &'a BTreeMap<String, f64>,
    depth: u64,
    max_depth: u64,
}

impl P<'_> {
    fn ws(&mut self) {
        while self.i < self.b.len() && self.b[self.i] == b' ' {
            self.i += 1;
        }
    }

    fn sum(&mut self) -> Result<f64, String> {
        let mut v = self.product()?;
        loop {
            self.ws();
            match self.b.get(self.i) {
                Some(b'+') => {
                    self.i += 1;
                    v += self.product()?;
                }
                Some(b'-') => {
                    self.i += 1;
                    v -= self.product()?;
                }
                _ => return Ok(v),
            }
        }
    }

    fn product(&mut self) -> Result<f64, String> {
        let mut v = self.atom()?;
        loop {
            self.ws();
            match self.b.get(self.i) {
                Some(b'*') => {
                    self.i += 1;
                    v *= self.atom()?;
                }
                Some(b'/') => {
                    self.i += 1;
                    v /= self.atom()?;
                }
                _ => return Ok(v),
            }
        }
    }

    /// One level deeper for a sign or a parenthesis, refused past the limit.
    fn nested<T>(&mut self, f: impl FnOnce(&mut Self) -> Result<T, String>) -> Result<T, String> {
        if self.depth >= self.max_depth {
            return Err(crate::Exceeded::new(
                "expression-depth",
                format!(
                    "at byte {} the expression nests signs and parentheses deeper than {}",
                    self.i + 1,
                    self.max_depth
                ),
                self.max_depth as f64,
            )
            .to_string());
        }
        self.depth += 1;
        let v = f(self);
        self.depth -= 1;
        v
    }

    fn atom(&mut self) -> Result<f64, String> {
        self.ws();
        let Some(&c) = self.b.get(self.i) else {
            return Err("missing value".into());
        };
        match c {
            b'-' | b'+' | b'(' => self.nested(Self::signed),
            _ => self.plain(),
        }
    }

    /// A signed or parenthesised value.
    fn signed(&mut self) -> Result<f64, String> {
        let c = self.b[self.i];
        match c {
            b'-' => {
                self.i += 1;
                Ok(-self.atom()?)
            }
            b'+' => {
                self.i += 1;
                self.atom()
            }
            b'(' => {
                self.i += 1;
                let v = self.sum()?;
                self.ws();
                if self.b.get(self.i) != Some(&b')') {
                    return Err("missing `)`".into());
                }
                self.i += 1;
                Ok(v)
            }
            _ => self.plain(),
        }
    }

    /// A number or a variable.
    fn plain(&mut self) -> Result<f64, String> {
        let c = self.b[self.i];
        match c {
            b'0'..=b'9' | b'.' => {
                let s = self.i;
                while self.i < self.b.len()
                    && (self.b[self.i].is_ascii_digit() || self.b[self.i] == b'.')
                {
                    self.i += 1;
                }
                if self.i < self.b.len() && matches!(self.b[self.i], b'e' | b'E') {
                    // exponent
                    let save = self.i;
                    self.i += 1;
                    if self.i < self.b.len() && matches!(self.b[self.i], b'-' | b'+') {
                        self.i += 1;
                    }
                    let ds = self.i;
                    while self.i < self.b.len() && self.b[self.i].is_ascii_digit() {
                        self.i += 1;
                    }
                    if ds == self.i {
                        self.i = save;
                    }
                }
                let t = std::str::from_utf8(&self.b[s..self.i]).map_err(|e| e.to_string())?;
                crate::diag::parse_num(t).ok_or_else(|| format!("`{t}` is not a number"))
            }
            c if c.is_ascii_alphabetic() || c == b'_' || c == b'#' || c == b'$' => {
                let s = self.i;
                self.i += 1;
                while self.i < self.b.len()
                    && (self.b[self.i].is_ascii_alphanumeric() || self.b[self.i] == b'_')
                {
                    self.i += 1;
                }
                let name = String::from_utf8_lossy(&self.b[s..self.i]).to_ascii_uppercase();
                self.ws();
                if self.b.get(self.i) == Some(&b'(') {
                    return Err(format!("function `{name}(...)` is not supported"));
                }
                self.vars
                    .get(&name)
                    .copied()
                    .ok_or_else(|| format!("variable `{name}` is not defined"))
            }
            _ => Err(format!("unexpected `{}`", c as char)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arithmetic_and_variables() {
        let mut v = BTreeMap::new();
        v.insert("_Z_HOME".to_string(), 610.0);
        assert_eq!(eval("_Z_HOME", &v), Ok(610.0));
        assert_eq!(eval("-(2+3)*_z_home/10", &v), Ok(-305.0));
        assert_eq!(eval(".02", &v), Ok(0.02));
        assert_eq!(eval("1e-3", &v), Ok(0.001));
        assert!(eval("_NOPE+1", &v).is_err());
        assert!(eval("AC(5)", &v).is_err());
        assert!(eval("2+", &v).is_err());
    }

    /// Issue 17: "a 12 KB Sinumerik expression of nested unary minus
    /// overflows the reader thread's stack (exit 134)". Nesting past the
    /// limit is an error naming the limit, on a small stack too.
    #[test]
    fn nesting_is_bounded() {
        let v = BTreeMap::new();
        assert_eq!(eval(&format!("{}5", "-".repeat(64)), &v), Ok(5.0));
        assert_eq!(
            eval(&format!("{}1{}", "(".repeat(63), ")".repeat(63)), &v),
            Ok(1.0)
        );
        for deep in [
            format!("{}5", "-".repeat(12_000)),
            format!("{}1", "(-".repeat(6_000)),
        ] {
            let e = std::thread::Builder::new()
                .stack_size(64 * 1024)
                .spawn(move || eval(&deep, &BTreeMap::new()))
                .expect("spawn")
                .join()
                .expect("no overflow");
            let e = e.expect_err("too deep");
            assert!(e.contains("expression-depth limit of 64"), "{e}");
        }
        assert_eq!(
            eval_within(&format!("{}5", "-".repeat(1000)), &v, 1000),
            Ok(5.0)
        );
    }
}
