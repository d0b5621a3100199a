//! Scene errors and where they are: the path of the offending field (`bodies[1].density`) and
//! its line in the scene's text.
//!
//! The text is scanned as RON (strings and comments skipped, brackets matched), so a path is
//! followed key by key and list entry by list entry: an error in the second `initial` entry
//! points at that entry, not the first.

use std::fmt;

/// A problem with a scene, located as precisely as possible.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// The scene file (or `<scene>` for a scene built in code).
    pub file: String,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// Path of the offending field, when known (e.g. `fluid.viscosity`, `bodies[1].density`;
    /// list entries are numbered from 0).
    pub field: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "scene error in {}", self.file)?;
        if let Some(l) = self.line {
            write!(f, ", line {l}")?;
        }
        if let Some(field) = &self.field {
            write!(f, ", field `{field}`")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SceneError {}

/// One step of a field path: a key or the index of a list entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seg {
    /// A key of a struct or map.
    Key(&'static str),
    /// The index of a list entry.
    Index(usize),
}

/// A failed check: the field's path (relative to the checked value until the caller puts it
/// [`under`](Issue::under) its own key) and the message.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Issue {
    pub path: Vec<Seg>,
    pub message: String,
}

/// The result of a check.
pub(crate) type Check<T = ()> = Result<T, Issue>;

impl Issue {
    /// An issue with the field at `path` (keys, relative to the checked value).
    pub fn new(path: &[&'static str], message: impl Into<String>) -> Issue {
        Issue {
            path: path.iter().map(|k| Seg::Key(k)).collect(),
            message: message.into(),
        }
    }

    /// The same issue seen from the value that holds the checked one at `seg`.
    pub fn under(mut self, seg: Seg) -> Issue {
        self.path.insert(0, seg);
        self
    }

    /// The issue as a [`SceneError`] of `file`, located in `text` if given.
    pub fn into_error(self, file: &str, text: Option<&str>) -> SceneError {
        SceneError {
            file: file.to_string(),
            line: text.and_then(|t| locate(t, &self.path)),
            field: Some(path_string(&self.path)),
            message: self.message,
        }
    }
}

/// Shorthand for `Err(Issue::new(path, message))`.
pub(crate) fn fail<T>(path: &[&'static str], message: impl Into<String>) -> Check<T> {
    Err(Issue::new(path, message))
}

/// `a.b[1].c`.
fn path_string(path: &[Seg]) -> String {
    let mut out = String::new();
    for s in path {
        match s {
            Seg::Key(k) => {
                if !out.is_empty() {
                    out.push('.');
                }
                out.push_str(k);
            }
            Seg::Index(i) => out.push_str(&format!("[{i}]")),
        }
    }
    out
}

/// The text with a flag per byte: true where it is code (not inside a string, a character
/// literal or a comment).
struct Code<'a> {
    text: &'a str,
    code: Vec<bool>,
}

impl<'a> Code<'a> {
    fn new(text: &'a str) -> Self {
        let b = text.as_bytes();
        let mut code = vec![true; b.len()];
        let mut i = 0;
        while i < b.len() {
            let start = i;
            match b[i] {
                b'"' | b'\'' => {
                    let q = b[i];
                    i += 1;
                    while i < b.len() && b[i] != q {
                        i += if b[i] == b'\\' { 2 } else { 1 };
                    }
                    i = (i + 1).min(b.len());
                }
                b'/' if b.get(i + 1) == Some(&b'/') => {
                    while i < b.len() && b[i] != b'\n' {
                        i += 1;
                    }
                }
                b'/' if b.get(i + 1) == Some(&b'*') => {
                    i += 2;
                    while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                        i += 1;
                    }
                    i = (i + 2).min(b.len());
                }
                _ => {
                    i += 1;
                    continue;
                }
            }
            code[start..i].iter_mut().for_each(|c| *c = false);
        }
        Code { text, code }
    }

    fn byte(&self, i: usize) -> Option<u8> {
        (self.code.get(i) == Some(&true)).then(|| self.text.as_bytes()[i])
    }

    fn line(&self, pos: usize) -> usize {
        self.text[..pos].matches('\n').count() + 1
    }

    /// The first `key` in `[from, to)` written as a field (`key:`) or a variant (`key(`).
    fn find_key(&self, from: usize, to: usize, key: &str) -> Option<usize> {
        let b = self.text.as_bytes();
        let mut start = from;
        while let Some(off) = self.text[start..to].find(key) {
            let pos = start + off;
            start = pos + key.len();
            if !self.code[pos] || (pos > 0 && is_ident(b[pos - 1])) {
                continue;
            }
            if b.get(start).is_some_and(|&c| is_ident(c)) {
                continue;
            }
            let rest = self.text[start..to].trim_start();
            if rest.starts_with(':') || rest.starts_with('(') {
                return Some(pos);
            }
        }
        None
    }

    /// The end of the value that starts at `from`: the first `,` or unmatched closing bracket
    /// outside brackets opened after `from`.
    fn value_end(&self, from: usize, to: usize) -> usize {
        let mut depth = 0usize;
        for i in from..to {
            match self.byte(i) {
                Some(b'(' | b'[' | b'{') => depth += 1,
                Some(b')' | b']' | b'}') => {
                    if depth == 0 {
                        return i;
                    }
                    depth -= 1;
                }
                Some(b',') if depth == 0 => return i,
                _ => {}
            }
        }
        to
    }

    /// The byte range of entry `index` of the first list opened in `[from, to)`.
    fn list_entry(&self, from: usize, to: usize, index: usize) -> Option<(usize, usize)> {
        let open = (from..to).find(|&i| self.byte(i) == Some(b'['))?;
        let mut start = open + 1;
        for _ in 0..index {
            let end = self.value_end(start, to);
            if self.byte(end) != Some(b',') {
                return None;
            }
            start = end + 1;
        }
        let skip = self.text[start..to].len() - self.text[start..to].trim_start().len();
        start += skip;
        let end = self.value_end(start, to);
        (end > start).then_some((start, end))
    }
}

fn is_ident(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

/// The line of the field at `path`, following keys and list entries; when part of the path
/// is not written (a default), the line of the deepest part that is.
pub fn locate(text: &str, path: &[Seg]) -> Option<usize> {
    let code = Code::new(text);
    let (mut from, mut to) = (0, text.len());
    let mut found = None;
    for seg in path {
        match *seg {
            Seg::Key(k) => match code.find_key(from, to, k) {
                Some(pos) => {
                    found = Some(pos);
                    to = code.value_end(pos, to);
                    from = pos;
                }
                None => break,
            },
            Seg::Index(i) => match code.list_entry(from, to, i) {
                Some((s, e)) => {
                    found = Some(s);
                    (from, to) = (s, e);
                }
                None => break,
            },
        }
    }
    found.map(|pos| code.line(pos))
}

/// The byte offset of a 1-based line and column (in characters).
pub fn offset_of(text: &str, line: usize, col: usize) -> usize {
    let line_start: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    let rest = &text[line_start.min(text.len())..];
    line_start
        + rest
            .char_indices()
            .nth(col.saturating_sub(1))
            .map_or(rest.len(), |(i, _)| i)
}

/// The path of the field being written at byte `pos` of `text` (`numerics.end_time`,
/// `initial[1].core_radius`), for errors the RON parser reports by position only.
pub fn path_at(text: &str, pos: usize) -> Option<String> {
    struct Frame {
        list: bool,
        key: Option<String>,
        index: usize,
    }
    let code = Code::new(text);
    let b = text.as_bytes();
    let pos = pos.min(text.len());
    let mut stack: Vec<Frame> = Vec::new();
    let mut i = 0;
    while i < pos {
        match code.byte(i) {
            Some(b'(' | b'{') => stack.push(Frame {
                list: false,
                key: None,
                index: 0,
            }),
            Some(b'[') => stack.push(Frame {
                list: true,
                key: None,
                index: 0,
            }),
            Some(b')' | b']' | b'}') => {
                stack.pop();
            }
            Some(b',') => {
                if let Some(f) = stack.last_mut() {
                    f.index += 1;
                    f.key = None;
                }
            }
            Some(c) if is_ident(c) && (i == 0 || !is_ident(b[i - 1])) => {
                let end = (i..text.len())
                    .find(|&j| !is_ident(b[j]))
                    .unwrap_or(text.len());
                if text[end..].trim_start().starts_with(':')
                    && let Some(f) = stack.last_mut()
                    && !f.list
                {
                    f.key = Some(text[i..end].to_string());
                }
                i = end;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    // An error reported at a key (an unknown or misplaced field) is about that key.
    let at = &text[pos..];
    let ident: String = at
        .bytes()
        .take_while(|&c| is_ident(c))
        .map(char::from)
        .collect();
    if !ident.is_empty()
        && at[ident.len()..].trim_start().starts_with(':')
        && let Some(f) = stack.last_mut()
        && !f.list
    {
        f.key = Some(ident);
    }
    // The outermost frame is `Scene(`: its keys are the top-level fields.
    let mut path = String::new();
    for f in &stack {
        if f.list {
            path.push_str(&format!("[{}]", f.index));
        } else if let Some(k) = &f.key {
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(k);
        }
    }
    (!path.is_empty()).then_some(path)
}
