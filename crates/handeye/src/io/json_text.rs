//! Places in JSON text. serde_json parses values but forgets where they were, and lets a key
//! repeated in one object replace the first silently; this scanner walks text that serde_json has
//! already accepted, once, to find the line of a value from its path or the first repeated key.
//!
//! Paths are written as the readers name fields: `name`, `name.inner`, `name[1][2]`.

use std::collections::HashMap;
use std::ops::ControlFlow;

/// One step of a path into a JSON document.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Step {
    /// A key of an object.
    Key(String),
    /// An element of an array, from 0.
    Index(usize),
}

/// A key given twice in one object.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct RepeatedKey {
    /// The field path of the key (`base_from_gripper.translation`).
    pub path: String,
    /// The key itself.
    pub key: String,
    /// Line of its first occurrence, from 1.
    pub first_line: usize,
    /// Line of its repetition, from 1.
    pub line: usize,
}

impl RepeatedKey {
    /// The message of the error that refuses it.
    pub fn message(&self) -> String {
        format!(
            "key `{}` given twice in one object (lines {} and {}): the second would silently replace the first",
            self.key, self.first_line, self.line
        )
    }
}

/// The first key repeated within one object anywhere in `text`.
pub(crate) fn repeated_key(text: &str) -> Option<RepeatedKey> {
    // The keys of every open object, with the line of each.
    let mut open: Vec<HashMap<String, usize>> = Vec::new();
    walk(text, |path, event| {
        match event {
            Event::Value { object: true, .. } => open.push(HashMap::new()),
            Event::Value { .. } => {}
            Event::ObjectEnd => {
                open.pop();
            }
            Event::Key { key, line } => {
                if let Some(keys) = open.last_mut()
                    && let Some(&first_line) = keys.get(key)
                {
                    let mut full = path.to_vec();
                    full.push(Step::Key(key.to_string()));
                    return ControlFlow::Break(RepeatedKey {
                        path: path_name(&full),
                        key: key.to_string(),
                        first_line,
                        line,
                    });
                }
                if let Some(keys) = open.last_mut() {
                    keys.insert(key.to_string(), line);
                }
            }
        }
        ControlFlow::Continue(())
    })
}

/// The line (from 1) where the value at `path` starts, or where the deepest value on the way to
/// it starts when the path goes further than the document; `None` when not even the first step
/// exists (the empty path is the whole document).
pub(crate) fn line_of(text: &str, path: &[Step]) -> Option<usize> {
    let mut deepest: Option<(usize, usize)> = None;
    let found = walk(text, |at, event| {
        if let Event::Value { line, .. } = event
            && at.len() <= path.len()
            && path.starts_with(at)
        {
            if at.len() == path.len() {
                return ControlFlow::Break(line);
            }
            if deepest.is_none_or(|(depth, _)| at.len() > depth) {
                deepest = Some((at.len(), line));
            }
        }
        ControlFlow::Continue(())
    });
    found.or(deepest.map(|(_, line)| line))
}

/// The line (from 1) where the value of `field` (a path such as `gripper_from_camera.matrix[1]`)
/// starts in `text`; 1 when not even its first step is there.
pub(crate) fn line_of_field(text: &str, field: &str) -> usize {
    line_of(text, &steps(field)).unwrap_or(1)
}

/// The steps of a field path as the readers write it (`a.b[1][2]`, `[0][1]`); a part that cannot
/// be read ends the path there.
pub(crate) fn steps(field: &str) -> Vec<Step> {
    let mut out = Vec::new();
    for part in field.split('.') {
        let (key, mut rest) = part.split_once('[').map_or((part, ""), |(k, r)| (k, r));
        if !key.is_empty() {
            out.push(Step::Key(key.to_string()));
        }
        while let Some((index, after)) = rest.split_once(']') {
            let Ok(k) = index.parse() else {
                return out;
            };
            out.push(Step::Index(k));
            rest = after.strip_prefix('[').unwrap_or(after);
        }
    }
    out
}

/// The field name of a path (`a.b[1][2]`).
pub(crate) fn path_name(path: &[Step]) -> String {
    let mut out = String::new();
    for step in path {
        match step {
            Step::Key(k) if out.is_empty() => out.push_str(k),
            Step::Key(k) => {
                out.push('.');
                out.push_str(k);
            }
            Step::Index(i) => out.push_str(&format!("[{i}]")),
        }
    }
    out
}

/// What the walk meets, with the path of the value or of the object holding the key.
enum Event<'a> {
    /// A value starts (an object when `object`).
    Value { line: usize, object: bool },
    /// A key of the innermost open object.
    Key { key: &'a str, line: usize },
    /// The innermost open object ends.
    ObjectEnd,
}

/// An open object or array.
struct Frame {
    object: bool,
    /// Objects: the next string is a key. Arrays: unused.
    expecting_key: bool,
    /// A step of this frame is on the path (a key read, or an array's element index).
    has_step: bool,
    /// Arrays: index of the current element.
    index: usize,
}

/// Walks JSON text, calling `visit` with the current path for each event until it breaks.
/// Never panics, whatever the text; on invalid JSON the places found are meaningless.
fn walk<T>(text: &str, mut visit: impl FnMut(&[Step], Event<'_>) -> ControlFlow<T>) -> Option<T> {
    let bytes = text.as_bytes();
    let mut path: Vec<Step> = Vec::new();
    let mut frames: Vec<Frame> = Vec::new();
    let (mut i, mut line) = (0, 1);
    while let Some(&b) = bytes.get(i) {
        let start = i;
        i += 1;
        let flow = match b {
            b'\n' => {
                line += 1;
                ControlFlow::Continue(())
            }
            b'{' | b'[' => {
                let flow = visit(
                    &path,
                    Event::Value {
                        line,
                        object: b == b'{',
                    },
                );
                frames.push(Frame {
                    object: b == b'{',
                    expecting_key: true,
                    has_step: b == b'[',
                    index: 0,
                });
                if b == b'[' {
                    path.push(Step::Index(0));
                }
                flow
            }
            b'}' | b']' => {
                if let Some(frame) = frames.pop() {
                    if frame.has_step {
                        path.pop();
                    }
                    if frame.object {
                        visit(&path, Event::ObjectEnd)
                    } else {
                        ControlFlow::Continue(())
                    }
                } else {
                    ControlFlow::Continue(())
                }
            }
            b',' => {
                if let Some(frame) = frames.last_mut() {
                    if frame.has_step {
                        path.pop();
                    }
                    if frame.object {
                        frame.expecting_key = true;
                        frame.has_step = false;
                    } else {
                        frame.index += 1;
                        path.push(Step::Index(frame.index));
                    }
                }
                ControlFlow::Continue(())
            }
            b'"' => {
                let end = string_end(bytes, start);
                let raw = text.get(start..end).unwrap_or("");
                let string_line = line;
                line += raw.matches('\n').count();
                i = end;
                match frames.last_mut() {
                    Some(frame) if frame.object && frame.expecting_key => {
                        frame.expecting_key = false;
                        frame.has_step = true;
                        let key: String =
                            serde_json::from_str(raw).unwrap_or_else(|_| raw.to_string());
                        let flow = visit(
                            &path,
                            Event::Key {
                                key: &key,
                                line: string_line,
                            },
                        );
                        path.push(Step::Key(key));
                        flow
                    }
                    _ => visit(
                        &path,
                        Event::Value {
                            line: string_line,
                            object: false,
                        },
                    ),
                }
            }
            b' ' | b'\t' | b'\r' | b':' => ControlFlow::Continue(()),
            _ => {
                // A number, `true`, `false` or `null`: runs to the next delimiter.
                while bytes
                    .get(i)
                    .is_some_and(|c| !b",]}\n \t\r:\"{[".contains(c))
                {
                    i += 1;
                }
                visit(
                    &path,
                    Event::Value {
                        line,
                        object: false,
                    },
                )
            }
        };
        if let ControlFlow::Break(t) = flow {
            return Some(t);
        }
    }
    None
}

/// The index just past the string starting with the quote at `start` (or the end of the text).
fn string_end(bytes: &[u8], start: usize) -> usize {
    let mut i = start + 1;
    while let Some(&b) = bytes.get(i) {
        match b {
            b'\\' => i += 2,
            b'"' => return i + 1,
            _ => i += 1,
        }
    }
    bytes.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str =
        "{\n \"a\": [1,\n  {\"b\": \"x,]\\\"\"},\n  [2, 3]],\n \"c\": {\"d\": null,\n\"d\" : 4}\n}";

    #[test]
    fn finds_the_line_of_a_path() {
        let at = |field: &str| line_of(TEXT, &steps(field));
        assert_eq!(at(""), Some(1));
        assert_eq!(at("a"), Some(2));
        assert_eq!(at("a[0]"), Some(2));
        assert_eq!(at("a[1].b"), Some(3));
        assert_eq!(at("a[2][1]"), Some(4));
        assert_eq!(at("c.d"), Some(5));
        // Deeper than the document: the deepest value on the way.
        assert_eq!(at("a[2][1][7].z"), Some(4));
        assert_eq!(at("zz"), Some(1));
    }

    #[test]
    fn finds_the_first_repeated_key() {
        let r = repeated_key(TEXT).unwrap();
        assert_eq!(
            (r.path.as_str(), r.key.as_str(), r.first_line, r.line),
            ("c.d", "d", 5, 6)
        );
        // Escapes name the same key; equal keys in different objects are not repeated.
        let r = repeated_key(r#"{"a": {"k": 1}, "b": {"k": 2}, "\u0061": 3}"#).unwrap();
        assert_eq!((r.path.as_str(), r.line), ("a", 1));
        assert_eq!(repeated_key(r#"[{"k": 1}, {"k": [{"k": 2}]}]"#), None);
    }

    #[test]
    fn paths_read_back() {
        for field in ["a", "a.b", "a[1][2]", "[0][1]", "[3][1].matrix[2][3]"] {
            assert_eq!(path_name(&steps(field)), field);
        }
    }

    proptest::proptest! {
        #[test]
        fn any_text_is_walked_without_panic(text in "[-{}\\[\\],:\"\\\\a-c0-9\n ]{0,60}") {
            let _ = repeated_key(&text);
            let _ = line_of(&text, &steps("a[1].b"));
        }
    }
}
