//! YAML documents as the peers' sample files write them, read by `yaml-rust2`'s event parser and
//! flattened to their scalars, each with its field path (`samples[2].robot.translation.x`,
//! `[0].effector_wrt_world[5]`) and its line, so that every error names both.
//!
//! Only what pose files use is accepted: one document (a second is refused) of mappings, sequences and scalars. An alias
//! (`*a`) or a key that is not a scalar is refused, and so is a key given twice in one mapping (as
//! in JSON, the second would silently replace the first).

use std::collections::BTreeMap;

use yaml_rust2::parser::{Event, MarkedEventReceiver, Parser};
use yaml_rust2::scanner::Marker;

use crate::io::parse_error;
use crate::model::error::Result;

/// The scalars of one YAML document by field path, and the length of each sequence.
#[derive(Debug, Default)]
pub(crate) struct YamlTree {
    /// Scalar text and its line (from 1), by path.
    scalars: BTreeMap<String, (String, usize)>,
    /// Number of items and the line where it starts, by the path of each sequence.
    sequences: BTreeMap<String, (usize, usize)>,
    /// The line where each value starts (its key's, in a mapping), by the value's path.
    keys: BTreeMap<String, usize>,
    file: String,
}

impl YamlTree {
    /// Reads `text` (named `file` in errors).
    pub fn parse(text: &str, file: &str) -> Result<Self> {
        // The parser places what ends the text on the line after its last one.
        let last_line = text.lines().count().max(1);
        let mut flattener = Flattener {
            last_line,
            ..Flattener::default()
        };
        let mut parser = Parser::new_from_str(text);
        // Every document is read, so that a second one is refused rather than ignored.
        parser.load(&mut flattener, true).map_err(|e| {
            parse_error(
                file,
                e.marker().line().clamp(1, last_line),
                "-",
                format!("malformed YAML: {}", e.info()),
            )
        })?;
        if let Some((line, field, message)) = flattener.problem {
            return Err(parse_error(file, line, field, message));
        }
        Ok(Self {
            scalars: flattener.scalars,
            sequences: flattener.sequences,
            keys: flattener.keys,
            file: file.to_string(),
        })
    }

    /// The text of the scalar at `path`, and its line.
    pub fn text(&self, path: &str) -> Option<(&str, usize)> {
        self.scalars.get(path).map(|(v, line)| (v.as_str(), *line))
    }

    /// The line where the value at `path` starts (its key's line in a mapping), if there is one.
    pub fn line(&self, path: &str) -> Option<usize> {
        self.keys.get(path).copied()
    }

    /// The length of the sequence at `path`, or an error naming what was expected there.
    pub fn sequence(&self, path: &str, expected: &str) -> Result<usize> {
        self.sequences
            .get(path)
            .map(|(n, _)| *n)
            .ok_or_else(|| self.missing(path, expected))
    }

    /// The line where the sequence at `path` starts, if it is one.
    pub fn line_of_sequence(&self, path: &str) -> Option<usize> {
        self.sequences.get(path).map(|(_, line)| *line)
    }

    /// The finite number at `path`; a missing one is an error saying what was `expected`.
    pub fn number(&self, path: &str, expected: &str) -> Result<f64> {
        let (text, line) = self
            .text(path)
            .ok_or_else(|| self.missing(path, expected))?;
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| {
                parse_error(
                    &self.file,
                    line,
                    path,
                    format!("`{text}`: expected a finite number"),
                )
            })
    }

    /// The error for a missing field, placed at the line of its closest present parent (the line
    /// of the key that names it, or where its sequence starts).
    pub fn missing(&self, path: &str, expected: &str) -> crate::model::error::Error {
        let line = parents(path)
            .find_map(|parent| {
                self.keys
                    .get(parent)
                    .copied()
                    .or_else(|| self.line_of_sequence(parent))
            })
            .unwrap_or(0);
        parse_error(&self.file, line, path, format!("missing ({expected})"))
    }
}

/// `a.b[2].c` → `a.b[2]`, `a.b`, `a` (nonempty parents, closest first).
fn parents(path: &str) -> impl Iterator<Item = &str> {
    let mut rest = path;
    std::iter::from_fn(move || {
        let cut = rest.rfind(['.', '['])?;
        rest = &rest[..cut];
        (!rest.is_empty()).then_some(rest)
    })
}

/// One open collection while the events of a document arrive.
enum Frame {
    Sequence {
        path: String,
        count: usize,
        line: usize,
    },
    Mapping {
        path: String,
        /// The key just read, whose value comes next, with its line.
        key: Option<(String, usize)>,
        /// Keys seen in this mapping, with their lines.
        seen: BTreeMap<String, usize>,
    },
}

#[derive(Default)]
struct Flattener {
    stack: Vec<Frame>,
    scalars: BTreeMap<String, (String, usize)>,
    sequences: BTreeMap<String, (usize, usize)>,
    keys: BTreeMap<String, usize>,
    /// The first problem found: line, field, message.
    problem: Option<(usize, String, String)>,
    /// The text's last line.
    last_line: usize,
    /// The documents begun so far.
    documents: usize,
}

impl Flattener {
    /// The path of the value that comes next in the open collection, or `None` when the next
    /// scalar of a mapping is a key (then `is_scalar` says whether it may be one).
    fn next_path(&mut self, is_scalar: Option<&str>, line: usize) -> Option<String> {
        match self.stack.last_mut() {
            None => Some(String::new()),
            Some(Frame::Sequence { path, count, .. }) => {
                *count += 1;
                let child = format!("{path}[{}]", *count - 1);
                self.keys.insert(child.clone(), line);
                Some(child)
            }
            Some(Frame::Mapping { path, key, seen }) => match key.take() {
                Some((k, key_line)) => {
                    let child = if path.is_empty() {
                        k
                    } else {
                        format!("{path}.{k}")
                    };
                    self.keys.insert(child.clone(), key_line);
                    Some(child)
                }
                None => {
                    let field = path.clone();
                    match is_scalar {
                        Some(k) => {
                            if let Some(first) = seen.insert(k.to_string(), line) {
                                self.problem.get_or_insert((
                                    line,
                                    if field.is_empty() {
                                        k.to_string()
                                    } else {
                                        format!("{field}.{k}")
                                    },
                                    format!(
                                        "key `{k}` given twice in one mapping (lines {first} and {line}): the second would silently replace the first"
                                    ),
                                ));
                            }
                            *key = Some((k.to_string(), line));
                        }
                        None => {
                            self.problem.get_or_insert((
                                line,
                                if field.is_empty() { "-".into() } else { field },
                                "a mapping key that is not a plain value".into(),
                            ));
                        }
                    }
                    None
                }
            },
        }
    }
}

impl MarkedEventReceiver for Flattener {
    fn on_event(&mut self, event: Event, mark: Marker) {
        if self.problem.is_some() {
            return;
        }
        let line = mark.line().clamp(1, self.last_line.max(1));
        match event {
            Event::Scalar(text, ..) => {
                if let Some(path) = self.next_path(Some(&text), line) {
                    self.scalars.insert(path, (text, line));
                }
            }
            Event::SequenceStart(..) => {
                if let Some(path) = self.next_path(None, line) {
                    self.stack.push(Frame::Sequence {
                        path,
                        count: 0,
                        line,
                    });
                }
            }
            Event::MappingStart(..) => {
                if let Some(path) = self.next_path(None, line) {
                    self.stack.push(Frame::Mapping {
                        path,
                        key: None,
                        seen: BTreeMap::new(),
                    });
                }
            }
            Event::SequenceEnd | Event::MappingEnd => {
                if let Some(Frame::Sequence { path, count, line }) = self.stack.pop() {
                    self.sequences.insert(path, (count, line));
                }
            }
            Event::Alias(_) => {
                self.problem = Some((
                    line,
                    "-".into(),
                    "a YAML alias (`*name`): write the values out".into(),
                ));
            }
            Event::DocumentStart => {
                self.documents += 1;
                if self.documents > 1 {
                    self.problem = Some((
                        line,
                        "-".into(),
                        "a second YAML document (after `---`): one is read, and which was meant is not known; keep one".into(),
                    ));
                }
            }
            Event::Nothing | Event::StreamStart | Event::StreamEnd | Event::DocumentEnd => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::error::Error;

    fn place(e: Error) -> (usize, String, String) {
        match e {
            Error::Parse {
                line,
                field,
                message,
                ..
            } => (line, field, message),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn flattens_block_and_flow_styles_with_lines() {
        let text = "a:\n  b: 1\n  c: [2, 3]\n- x\n";
        assert!(YamlTree::parse(text, "f.yaml").is_err());
        let text = "samples:\n- robot:\n    translation: {x: 1, y: 2.5, z: -3}\n  tracking:\n    - 4\n    - 5\n";
        let t = YamlTree::parse(text, "f.yaml").unwrap();
        assert_eq!(t.text("samples[0].robot.translation.y"), Some(("2.5", 3)));
        assert_eq!(t.number("samples[0].tracking[1]", "").unwrap(), 5.0);
        assert_eq!(t.sequence("samples", "").unwrap(), 1);
        assert_eq!(t.sequence("samples[0].tracking", "").unwrap(), 2);
    }

    #[test]
    fn names_the_place_of_every_problem() {
        let (line, field, message) =
            place(YamlTree::parse("a:\n  b: 1\n  b: 2\n", "f.yaml").unwrap_err());
        assert_eq!((line, field.as_str()), (3, "a.b"));
        assert!(message.contains("given twice"), "{message}");
        let (line, _, message) = place(YamlTree::parse("a: &x 1\nb: *x\n", "f.yaml").unwrap_err());
        assert_eq!(line, 2);
        assert!(message.contains("alias"), "{message}");
        let (line, _, message) = place(YamlTree::parse("a: [1, 2\nb: 3\n", "f.yaml").unwrap_err());
        assert!(
            line >= 1 && message.starts_with("malformed YAML"),
            "{message}"
        );
        let t = YamlTree::parse("s:\n- r:\n    x: one\n", "f.yaml").unwrap();
        let (line, field, message) = place(t.number("s[0].r.x", "").unwrap_err());
        assert_eq!((line, field.as_str()), (3, "s[0].r.x"));
        assert!(message.contains("`one`"), "{message}");
        // A missing field is placed at the key of the mapping that lacks it (`r:`).
        let (line, field, message) = place(t.number("s[0].r.y", "a number").unwrap_err());
        assert_eq!((line, field.as_str()), (2, "s[0].r.y"));
        assert!(message.contains("missing (a number)"), "{message}");
    }

    /// A second document is refused at its `---`, not ignored; one document after a directive
    /// (OpenCV's `%YAML:1.0` then `---`) is one document.
    #[test]
    fn a_second_document_is_refused_where_it_starts() {
        let (line, _, message) = place(YamlTree::parse("a: 1\n---\na: 2\n", "f.yaml").unwrap_err());
        assert_eq!(line, 2);
        assert!(message.contains("second YAML document"), "{message}");
        let t = YamlTree::parse("%YAML 1.2\n---\na: 1\n", "f.yaml").unwrap();
        assert_eq!(t.number("a", "").unwrap(), 1.0);
        let t = YamlTree::parse("---\na: 1\n...\n", "f.yaml").unwrap();
        assert_eq!(t.number("a", "").unwrap(), 1.0);
    }
}
