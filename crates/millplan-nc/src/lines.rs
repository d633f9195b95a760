//! The one line splitter every reader is fed through: a line ends at LF, at
//! CRLF or at a lone CR (old Macintosh and some DNC transfers write CR only;
//! read as one line, a five-block program would become one block).

/// The lines of `src` without their terminators. Like `str::split('\n')`,
/// text after the last terminator is one more line (empty when the text ends
/// with a terminator).
pub fn split(src: &str) -> Lines<'_> {
    Lines { rest: Some(src) }
}

/// Iterator of [`split`].
pub struct Lines<'a> {
    rest: Option<&'a str>,
}

impl<'a> Iterator for Lines<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        let s = self.rest?;
        match memchr::memchr2(b'\n', b'\r', s.as_bytes()) {
            Some(i) => {
                let crlf = s.as_bytes()[i] == b'\r' && s.as_bytes().get(i + 1) == Some(&b'\n');
                self.rest = Some(&s[i + if crlf { 2 } else { 1 }..]);
                Some(&s[..i])
            }
            None => {
                self.rest = None;
                Some(s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_line_ending_splits_alike() {
        for nl in ["\n", "\r\n", "\r"] {
            let src = ["G0 X1", "", "G1 Y2", "M30"].join(nl) + nl;
            assert_eq!(
                split(&src).collect::<Vec<_>>(),
                ["G0 X1", "", "G1 Y2", "M30", ""],
                "{nl:?}"
            );
        }
        assert_eq!(
            split("a\r\rb\n\rc").collect::<Vec<_>>(),
            ["a", "", "b", "", "c"]
        );
        assert_eq!(split("").collect::<Vec<_>>(), [""]);
        assert_eq!(
            split("x\ny").collect::<Vec<_>>(),
            "x\ny".split('\n').collect::<Vec<_>>()
        );
    }
}
