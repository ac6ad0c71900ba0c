//! Where in a JSON text a parser stopped, as a field path (`chunks[2].actions[5][0]`): serde
//! reports only line and column, and a number out of range (`1e400`) or a `NaN` literal is
//! easier to fix when the field is named.

/// The path of the value at 1-based `line` and `column` of `text` (as `serde_json` reports
/// them): object keys joined by `.`, array indices in brackets; `None` at the top level or past
/// the end of the text. The text before that point is scanned leniently (it parsed already).
pub fn json_path_at(text: &str, line: usize, column: usize) -> Option<String> {
    let start = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum::<usize>();
    let end = (start + column.saturating_sub(1)).min(text.len());
    enum Frame {
        Object { key: Option<String>, want_key: bool },
        Array(usize),
    }
    let mut stack: Vec<Frame> = Vec::new();
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < end {
        match bytes[i] {
            b'{' => stack.push(Frame::Object {
                key: None,
                want_key: true,
            }),
            b'[' => stack.push(Frame::Array(0)),
            b'}' | b']' => {
                stack.pop();
            }
            b',' => match stack.last_mut() {
                Some(Frame::Array(k)) => *k += 1,
                Some(Frame::Object { key, want_key }) => {
                    *key = None;
                    *want_key = true;
                }
                None => {}
            },
            b'"' => {
                let mut j = i + 1;
                let mut s = Vec::new();
                while j < bytes.len() && bytes[j] != b'"' {
                    if bytes[j] == b'\\' {
                        j += 1;
                    }
                    if let Some(&b) = bytes.get(j) {
                        s.push(b);
                    }
                    j += 1;
                }
                if let Some(Frame::Object { key, want_key }) = stack.last_mut()
                    && *want_key
                {
                    *key = Some(String::from_utf8_lossy(&s).into_owned());
                    *want_key = false;
                }
                i = j;
            }
            _ => {}
        }
        i += 1;
    }
    // At an object's closing brace (`missing field`), the error is the object's, not its last
    // key's.
    if bytes.get(end) == Some(&b'}')
        && let Some(Frame::Object { key, .. }) = stack.last_mut()
    {
        *key = None;
    }
    let mut path = String::new();
    for f in &stack {
        match f {
            Frame::Object { key: Some(k), .. } => {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(k);
            }
            Frame::Object { key: None, .. } => {}
            Frame::Array(k) => path.push_str(&format!("[{k}]")),
        }
    }
    (!path.is_empty()).then_some(path)
}

/// A `serde_json` error with the field path in front where the error has a position:
/// `chunks[2].actions[5][0]: number out of range at line 12 column 40`; a number out of range
/// or a non-JSON literal (`NaN`, `Infinity`) gets a hint that values must be finite.
pub fn describe_json_error(text: &str, e: &serde_json::Error) -> String {
    // Editors on some systems start a file with a byte-order mark: named, not "expected value".
    if text.starts_with('\u{feff}') && e.line() == 1 && e.column() <= 1 {
        return "the file starts with a UTF-8 byte order mark (EF BB BF); JSON input is UTF-8 without BOM: remove it".into();
    }
    let msg = e.to_string();
    // The character serde stopped at (its column counts from 1), for the hint.
    let at = (e.line() > 0 && e.column() > 0)
        .then(|| text.lines().nth(e.line() - 1))
        .flatten()
        .and_then(|l| l.chars().nth(e.column() - 1));
    let hint = if msg.starts_with("number out of range") {
        " (numbers must be finite: |x| ≤ 1.8e308)"
    } else if msg.starts_with("expected value") {
        match at {
            Some('+') => " (a JSON number has no leading `+`)",
            Some('.') => " (a JSON number has a digit before its `.`)",
            Some('N' | 'I' | 'n' | 'i' | '-') => {
                " (NaN and Infinity are not JSON: numbers must be finite)"
            }
            _ => " (not a JSON value: a number, string, true, false, null, array or object)",
        }
    } else {
        ""
    };
    match (e.line() > 0)
        .then(|| json_path_at(text, e.line(), e.column()))
        .flatten()
    {
        Some(p) => format!("{p}: {msg}{hint}"),
        None => format!("{msg}{hint}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path_of(text: &str) -> String {
        let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
        describe_json_error(text, &e)
    }

    #[test]
    fn paths_name_the_field_of_the_bad_number() {
        let got: Vec<String> = [
            "{\"a\": 1, \"chunks\": [{\"t\": 0}, {\"actions\": [[1, 2], [3, 1e400]]}]}",
            "{\n  \"start\": [0.0,\n    NaN]\n}",
            // Keys with commas and escaped quotes inside strings do not confuse the scan.
            "{\"x,\\\"y\": \"a,b\", \"z\": {\"w\": -1e999}}",
            "[1e400]",
        ]
        .into_iter()
        .map(path_of)
        .collect();
        assert_eq!(
            got,
            [
                "chunks[1].actions[1][1]: number out of range at line 1 column 60 (numbers must be finite: |x| ≤ 1.8e308)",
                "start[1]: expected value at line 3 column 5 (NaN and Infinity are not JSON: numbers must be finite)",
                "z.w: number out of range at line 1 column 34 (numbers must be finite: |x| ≤ 1.8e308)",
                "[0]: number out of range at line 1 column 6 (numbers must be finite: |x| ≤ 1.8e308)",
            ]
        );
        assert_eq!(json_path_at("{}", 1, 1), None);
        // A missing field is the object's error: its path, not its last key's.
        #[derive(Debug, serde::Deserialize)]
        #[allow(dead_code)]
        struct Inner {
            b: f64,
            c: f64,
        }
        #[derive(Debug, serde::Deserialize)]
        #[allow(dead_code)]
        struct Outer {
            a: Vec<Inner>,
        }
        let text = "{\"a\": [{\"b\": 1, \"c\": 2}, {\"b\": 1}]}";
        let e = serde_json::from_str::<Outer>(text).unwrap_err();
        assert_eq!(
            describe_json_error(text, &e),
            "a[1]: missing field `c` at line 1 column 33"
        );
    }

    /// The hint names what is wrong with the value serde could not read.
    #[test]
    fn a_value_that_is_not_json_is_named() {
        let hint = |text: &str| {
            let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
            describe_json_error(text, &e)
        };
        assert!(hint("{\"t\": +1}").ends_with("(a JSON number has no leading `+`)"));
        assert!(hint("{\"t\": .5}").ends_with("(a JSON number has a digit before its `.`)"));
        assert!(hint("{\"t\": NaN}").contains("NaN and Infinity are not JSON"));
        assert!(hint("{\"t\": yes}").contains("not a JSON value"));
    }
}

#[cfg(test)]
mod bom_tests {
    use super::describe_json_error;

    /// A file that starts with a UTF-8 byte-order mark is told so, not "expected value at line 1
    /// column 1"; a BOM-less error keeps its own message.
    #[test]
    fn a_byte_order_mark_is_named() {
        let text = "\u{feff}{\"a\": 1}";
        let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
        let msg = describe_json_error(text, &e);
        assert!(msg.contains("byte order mark (EF BB BF)"), "{msg}");
        let text = "{\"a\": }";
        let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
        assert!(!describe_json_error(text, &e).contains("byte order mark"));
    }
}
