//! Error messages as a command prints them: long words and paths
//! shortened (a path loses only the middle of its folder, never its file
//! name, line and column), control characters escaped, and the place a
//! message names (`file:line:col: `) taken apart for the JSON form.

use serde::Serialize;

/// Longest word of a message printed whole; a longer one (a 1 MB token the
/// input held) is cut to its start and its length.
const LONGEST_WORD: usize = 80;

/// `message` with every word (a run without whitespace) longer than
/// `LONGEST_WORD` bytes shortened: a path to the middle of its folder, any
/// other word to its first 40 characters, `…` and its length in bytes.
pub fn shorten(message: &str) -> std::borrow::Cow<'_, str> {
    let long = |w: &str| w.len() > LONGEST_WORD;
    if !message.split_whitespace().any(long) {
        return std::borrow::Cow::Borrowed(message);
    }
    let mut out = String::with_capacity(256);
    let mut rest = message;
    while !rest.is_empty() {
        let ws = rest
            .find(|c: char| !c.is_whitespace())
            .unwrap_or(rest.len());
        out.push_str(&rest[..ws]);
        rest = &rest[ws..];
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let word = &rest[..end];
        if long(word) && word.len() - word.rfind(['/', '\\']).unwrap_or(0) <= LONGEST_WORD {
            // A path: its folder's middle goes, its file name stays.
            out.push_str(&shorten_path(word));
        } else if long(word) {
            let head: String = word.chars().take(40).collect();
            out.push_str(&format!("{head}…[{} bytes]", word.len()));
        } else {
            out.push_str(word);
        }
        rest = &rest[end..];
    }
    std::borrow::Cow::Owned(out)
}

/// Longest path printed whole in a text message: any path a person would
/// type or an editor would jump to (`file:line:col`) is printed whole; only
/// absurd ones are cut.
const LONGEST_PATH: usize = 160;

/// `path` as printed in a text message: whole when short, else with only the
/// middle of its folder replaced by `…`; the file name is never cut.
fn shorten_path(path: &str) -> std::borrow::Cow<'_, str> {
    if path.chars().count() <= LONGEST_PATH {
        return std::borrow::Cow::Borrowed(path);
    }
    let Some(slash) = path.rfind(['/', '\\']) else {
        return std::borrow::Cow::Borrowed(path);
    };
    let (dir, name) = path.split_at(slash);
    let n = dir.chars().count();
    let keep = LONGEST_PATH.saturating_sub(name.chars().count()).max(16) / 2;
    if n <= 2 * keep {
        return std::borrow::Cow::Borrowed(path);
    }
    let head: String = dir.chars().take(keep).collect();
    let tail: String = dir.chars().skip(n - keep).collect();
    std::borrow::Cow::Owned(format!("{head}…{tail}{name}"))
}

/// A message as printed in text: the located file (`file:line:col: `,
/// `file:byte N: `, `file: `) with only the middle of its folder shortened,
/// its location whole, and the long words of the rest cut by [`shorten`].
/// Control characters (an ESC in a file name would drive the terminal) are
/// written as escapes (`\u{1b}`); line breaks and tabs stay.
pub fn text(message: &str) -> String {
    let (file, _, _, rest) = locate(message);
    let Some(file) = file else {
        return escape_controls(&shorten(message));
    };
    let place = &message[file.len()..message.len() - rest.len()];
    escape_controls(&format!("{}{place}{}", shorten_path(file), shorten(rest)))
}

/// `s` with every control character but a line break or tab escaped.
pub fn escape_controls(s: &str) -> String {
    if !s.chars().any(|c| c.is_control() && c != '\n' && c != '\t') {
        return s.to_string();
    }
    s.chars()
        .map(|c| match c {
            '\n' | '\t' => c.to_string(),
            c if c.is_control() => c.escape_unicode().to_string(),
            c => c.to_string(),
        })
        .collect()
}

/// `file`, `line` and `col` of a message that starts `file:line:col: `, and
/// the rest of the message. A binary STL's `file:byte N: ` has no line; its
/// `col` is the byte offset N. `file: what` names the file alone.
pub fn locate(message: &str) -> (Option<&str>, Option<u64>, Option<u64>, &str) {
    let digits = |s: &str| -> Option<(u64, usize)> {
        let n = s.bytes().take_while(u8::is_ascii_digit).count();
        s[..n].parse().ok().map(|v| (v, n))
    };
    for (i, _) in message.match_indices(':') {
        let rest = &message[i + 1..];
        if let Some((line, n)) = digits(rest) {
            let after = &rest[n..];
            if let Some(c) = after.strip_prefix(':') {
                if let Some((col, m)) = digits(c) {
                    if let Some(msg) = c[m..].strip_prefix(": ") {
                        return (Some(&message[..i]), Some(line), Some(col), msg);
                    }
                }
            }
        }
        if let Some(b) = rest.strip_prefix("byte ") {
            if let Some((byte, n)) = digits(b) {
                if let Some(msg) = b[n..].strip_prefix(": ") {
                    return (Some(&message[..i]), None, Some(byte), msg);
                }
            }
        }
    }
    // `file: what`: a path is one word that is not an option.
    match message.split_once(": ") {
        Some((file, rest)) if !file.contains(char::is_whitespace) && !file.starts_with('-') => {
            (Some(file), None, None, rest)
        }
        _ => (None, None, None, message),
    }
}

/// An error as `--json` prints it on standard error.
#[derive(Serialize)]
pub struct ErrorJson<'a> {
    pub error: ErrorBody<'a>,
}

/// The fields of [`ErrorJson`]; what the message does not say is null.
#[derive(Serialize)]
pub struct ErrorBody<'a> {
    /// `usage`, `bad-input`, `findings` or `internal`.
    pub code: &'a str,
    pub col: Option<u64>,
    pub exit: i32,
    pub file: Option<&'a str>,
    pub line: Option<u64>,
    pub message: std::borrow::Cow<'a, str>,
}

/// An error as one line of JSON, `{"error": {"file", "line", "col", "code",
/// "exit", "message"}}`, `code` the exit code's stable name; the file is
/// given whole, the long words of the message are cut by [`shorten`].
pub fn json(message: &str, exit: i32, code: &str) -> String {
    let (file, line, col, rest) = locate(message);
    let body = ErrorBody {
        code,
        col,
        exit,
        file,
        line,
        message: shorten(rest),
    };
    serde_json::to_string(&ErrorJson { error: body }).unwrap_or_default()
}

/// A usage error as the argument parser printed it, on one line for the
/// JSON form: its usage lines and its leading `error: ` dropped.
pub fn usage_line(printed: &str) -> String {
    let what = printed.split("\n\nUsage:").next().unwrap_or("");
    let what: Vec<&str> = what
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    what.join(" ").trim_start_matches("error: ").to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_errors_name_their_place() {
        let v: serde_json::Value =
            serde_json::from_str(&json("dir/a:b.nc:12:7: `Q` is not a word", 2, "bad-input"))
                .expect("json");
        let e = &v["error"];
        assert_eq!(e["file"], "dir/a:b.nc");
        assert_eq!((e["line"].as_u64(), e["col"].as_u64()), (Some(12), Some(7)));
        assert_eq!(e["code"], "bad-input");
        assert_eq!(e["message"], "`Q` is not a word");
        let v: serde_json::Value =
            serde_json::from_str(&json("bad.stl:byte 80: short file", 2, "bad-input"))
                .expect("json");
        assert_eq!(v["error"]["col"], 80);
        assert!(v["error"]["line"].is_null());
        let v: serde_json::Value =
            serde_json::from_str(&json("--step 0: must be a number", 2, "usage")).expect("json");
        assert!(v["error"]["file"].is_null());
        assert_eq!(v["error"]["code"], "usage");
        assert_eq!(v["error"]["message"], "--step 0: must be a number");
        let v: serde_json::Value =
            serde_json::from_str(&json("/no/such.apt: cannot open", 2, "bad-input")).expect("json");
        assert_eq!(v["error"]["file"], "/no/such.apt");
        assert_eq!(v["error"]["message"], "cannot open");
    }

    /// A long folder loses its middle; file name, line and column stay.
    #[test]
    fn long_paths_keep_their_location() {
        let dir = format!("/srv/cam/{}/last", "d".repeat(300));
        let m = format!("{dir}/part 1.nc:6:4: `1..5` is not a number");
        let t = text(&m);
        assert!(t.starts_with("/srv/cam/ddd"), "{t}");
        assert!(
            t.ends_with("d/last/part 1.nc:6:4: `1..5` is not a number"),
            "{t}"
        );
        assert!(t.chars().count() < 200, "{t}");
        assert_eq!(text("a.nc:1:2: short"), "a.nc:1:2: short");
        // A real absolute path, as an editor jumps to it, stays whole.
        let real = "/work/shared/data/nx-posted-gcode-samples/bridgeport412_heidenhain_3axis_inch.ptp:101:1: x";
        assert_eq!(text(real), real);
        let m = format!("--stl {dir}/p.stl: no triangles");
        let t = text(&m);
        assert!(
            t.ends_with("/last/p.stl: no triangles") && t.contains('…'),
            "{t}"
        );
    }

    /// Issue 17: "error messages echo a whole 1 MB token".
    #[test]
    fn long_words_are_cut() {
        let token = "9".repeat(1_000_000);
        let m = format!("f.nc:4:4: `{token}` is not a number after `X`");
        let s = shorten(&m);
        assert!(s.len() < 200, "{s}");
        assert!(s.starts_with("f.nc:4:4: `9999"), "{s}");
        assert!(
            s.ends_with("…[1000002 bytes] is not a number after `X`"),
            "{s}"
        );
        assert_eq!(shorten("short words stay"), "short words stay");
        assert_eq!(
            shorten(&"é".repeat(100))
                .chars()
                .filter(|c| *c == 'é')
                .count(),
            40
        );
    }

    #[test]
    fn usage_errors_fit_one_line() {
        let printed = "error: unexpected argument '--nope' found\n\n  tip: to pass '--nope' as a value, use '-- --nope'\n\nUsage: millplan inspect <FILE>\n\nFor more information, try '--help'.\n";
        assert_eq!(
            usage_line(printed),
            "unexpected argument '--nope' found tip: to pass '--nope' as a value, use '-- --nope'"
        );
    }
}
