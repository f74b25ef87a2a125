//! A RON syntax tree with byte spans: where each value starts and ends in the text, so an edit
//! replaces exactly the text of one value.

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Atom {
    Int,
    Float,
    Str,
    Char,
    Bool,
    Ident,
}

#[derive(Debug)]
pub(crate) enum Kind {
    Atom(Atom),
    /// `Name(a: 1, b: 2)` or `(a: 1)`; `()` is an empty struct.
    Struct(Vec<(String, Node)>),
    /// `Name(1, 2)`, `Some(x)`, `(1.0, 2.0)`.
    Tuple(Option<String>, Vec<Node>),
    Seq(Vec<Node>),
    Map(Vec<(Node, Node)>),
}

#[derive(Debug)]
pub(crate) struct Node {
    pub(crate) start: usize,
    pub(crate) end: usize,
    pub(crate) kind: Kind,
    /// For containers: the byte offset of the closing bracket, and whether the last entry is
    /// followed by a comma.
    pub(crate) close: usize,
    pub(crate) trailing_comma: bool,
}

impl Node {
    pub(crate) fn describe(&self, text: Option<&str>) -> String {
        match &self.kind {
            Kind::Atom(Atom::Ident) => match text {
                Some(t) => format!("`{}`", &t[self.start..self.end]),
                None => "a name".into(),
            },
            Kind::Atom(a) => a_name(*a),
            Kind::Struct(_) => "a struct".into(),
            Kind::Tuple(..) => "a tuple".into(),
            Kind::Seq(_) => "a list".into(),
            Kind::Map(_) => "a map".into(),
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        match &self.kind {
            Kind::Struct(f) => f.is_empty(),
            Kind::Tuple(_, i) | Kind::Seq(i) => i.is_empty(),
            Kind::Map(e) => e.is_empty(),
            Kind::Atom(_) => true,
        }
    }

    /// The atom a value holds, looking through `Some(…)`.
    pub(crate) fn atom(&self) -> Option<Atom> {
        match &self.kind {
            Kind::Atom(a) => Some(*a),
            Kind::Tuple(Some(n), items) if n == "Some" && items.len() == 1 => items[0].atom(),
            _ => None,
        }
    }
}

/// `a number`, `an integer`.
pub(crate) fn a_name(a: Atom) -> String {
    let n = atom_name(a);
    let article = if n.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("{article} {n}")
}

pub(crate) fn atom_name(a: Atom) -> &'static str {
    match a {
        Atom::Int => "integer",
        Atom::Float => "number",
        Atom::Str => "string",
        Atom::Char => "character",
        Atom::Bool => "boolean",
        Atom::Ident => "name",
    }
}

/// Parse one RON value filling `text` (a leading `#![enable(…)]` and comments allowed).
/// On error, the byte offset and what was expected.
pub(crate) fn parse_ron(text: &str) -> Result<Node, (usize, String)> {
    let mut p = Parser {
        s: text.as_bytes(),
        at: 0,
        depth: 0,
    };
    p.skip();
    while p.s[p.at..].starts_with(b"#![") {
        match p.s[p.at..].iter().position(|&c| c == b']') {
            Some(k) => p.at += k + 1,
            None => return Err((p.at, "an unclosed `#![`".into())),
        }
        p.skip();
    }
    let node = p.value()?;
    p.skip();
    if p.at != p.s.len() {
        return Err((p.at, "unexpected text after the value".into()));
    }
    Ok(node)
}

pub(crate) struct Parser<'a> {
    s: &'a [u8],
    at: usize,
    /// How many containers enclose the value being read (at most [`crate::MAX_DEPTH`]).
    depth: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.at).copied()
    }

    /// Skip whitespace and comments (`//…`, nested `/* … */`).
    fn skip(&mut self) {
        loop {
            while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
                self.at += 1;
            }
            if self.s[self.at..].starts_with(b"//") {
                while self.peek().is_some_and(|c| c != b'\n') {
                    self.at += 1;
                }
            } else if self.s[self.at..].starts_with(b"/*") {
                let mut depth = 0usize;
                while self.at < self.s.len() {
                    if self.s[self.at..].starts_with(b"/*") {
                        depth += 1;
                        self.at += 2;
                    } else if self.s[self.at..].starts_with(b"*/") {
                        depth -= 1;
                        self.at += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        self.at += 1;
                    }
                }
            } else {
                return;
            }
        }
    }

    fn err<T>(&self, what: &str) -> Result<T, (usize, String)> {
        let found = match self.peek() {
            None => "the end".to_string(),
            Some(_) => {
                let rest = String::from_utf8_lossy(&self.s[self.at..]);
                format!("`{}`", rest.chars().take(12).collect::<String>())
            }
        };
        Err((self.at, format!("expected {what}, found {found}")))
    }

    pub(crate) fn is_ident_start(c: u8) -> bool {
        c.is_ascii_alphabetic() || c == b'_' || c >= 0x80
    }

    pub(crate) fn is_ident(c: u8) -> bool {
        c.is_ascii_alphanumeric() || c == b'_' || c >= 0x80
    }

    fn ident(&mut self) -> String {
        let start = self.at;
        if self.s[self.at..].starts_with(b"r#") {
            self.at += 2;
        }
        while self.peek().is_some_and(Self::is_ident) {
            self.at += 1;
        }
        String::from_utf8_lossy(&self.s[start..self.at])
            .trim_start_matches("r#")
            .to_string()
    }

    /// One value; a container counts one level of nesting while its contents are read, and a
    /// value nested deeper than [`crate::MAX_DEPTH`] is refused (the parser recurses once per
    /// level, so the cap keeps it on its stack whatever the text).
    fn value(&mut self) -> Result<Node, (usize, String)> {
        if self.depth > crate::MAX_DEPTH {
            return Err((
                self.at,
                format!(
                    "nested deeper than {} levels, the most a scene may nest",
                    crate::MAX_DEPTH
                ),
            ));
        }
        self.depth += 1;
        let node = self.value_here();
        self.depth -= 1;
        node
    }

    fn value_here(&mut self) -> Result<Node, (usize, String)> {
        self.skip();
        let start = self.at;
        let atom = |p: &Self, a| Node {
            start,
            end: p.at,
            kind: Kind::Atom(a),
            close: p.at,
            trailing_comma: false,
        };
        match self.peek() {
            None => self.err("a value"),
            Some(b'(') => self.paren(start, None),
            Some(b'[') => {
                let (items, close, trailing) = self.list(b']')?;
                Ok(Node {
                    start,
                    end: self.at,
                    kind: Kind::Seq(items),
                    close,
                    trailing_comma: trailing,
                })
            }
            Some(b'{') => self.map(start),
            Some(b'"') => {
                self.string()?;
                Ok(atom(self, Atom::Str))
            }
            Some(b'\'') => {
                self.at += 1;
                while let Some(c) = self.peek() {
                    self.at += 1;
                    match c {
                        b'\\' => self.at += 1,
                        b'\'' => return Ok(atom(self, Atom::Char)),
                        _ => {}
                    }
                }
                self.err("a closing `'`")
            }
            Some(b'r' | b'b') if self.raw_or_byte_string()? => Ok(atom(self, Atom::Str)),
            Some(c) if c.is_ascii_digit() || c == b'+' || c == b'-' || c == b'.' => {
                self.at += 1;
                let mut float = c == b'.';
                let hex = self.s[start..].starts_with(b"0x") || self.s[start..].starts_with(b"0b");
                while let Some(c) = self.peek() {
                    let exponent_sign = (c == b'+' || c == b'-')
                        && !hex
                        && matches!(self.s[self.at - 1], b'e' | b'E');
                    if Self::is_ident(c) || c == b'.' || exponent_sign {
                        float |= !hex && (c == b'.' || c == b'e' || c == b'E');
                        self.at += 1;
                    } else {
                        break;
                    }
                }
                let word = &self.s[start..self.at];
                float |= word.ends_with(b"inf") || word.ends_with(b"NaN");
                Ok(atom(self, if float { Atom::Float } else { Atom::Int }))
            }
            Some(c) if Self::is_ident_start(c) => {
                let name = self.ident();
                let ident_end = self.at;
                self.skip();
                if self.peek() == Some(b'(') {
                    return self.paren(start, Some(name));
                }
                self.at = ident_end;
                let a = match name.as_str() {
                    "true" | "false" => Atom::Bool,
                    "inf" | "NaN" => Atom::Float,
                    _ => Atom::Ident,
                };
                Ok(atom(self, a))
            }
            Some(_) => self.err("a value"),
        }
    }

    /// A raw string `r"…"`, `r#"…"#` or a byte string `b"…"`; false if it is an identifier.
    fn raw_or_byte_string(&mut self) -> Result<bool, (usize, String)> {
        let rest = &self.s[self.at..];
        if rest.starts_with(b"b\"") {
            self.at += 1;
            self.string()?;
            return Ok(true);
        }
        let hashes = rest[1..].iter().take_while(|&&c| c == b'#').count();
        if !(rest.first() == Some(&b'r') && rest.get(1 + hashes) == Some(&b'"')) {
            return Ok(false);
        }
        self.at += 2 + hashes;
        let mut end = b"\"".to_vec();
        end.extend(std::iter::repeat_n(b'#', hashes));
        match self.s[self.at..].windows(end.len()).position(|w| w == end) {
            Some(k) => {
                self.at += k + end.len();
                Ok(true)
            }
            None => self.err("the end of a raw string"),
        }
    }

    fn string(&mut self) -> Result<(), (usize, String)> {
        self.at += 1;
        while let Some(c) = self.peek() {
            self.at += 1;
            match c {
                b'\\' => self.at += 1,
                b'"' => return Ok(()),
                _ => {}
            }
        }
        self.err("a closing `\"`")
    }

    /// Items separated by commas up to `close`; returns them, the closing offset and whether
    /// a comma follows the last.
    fn list(&mut self, close: u8) -> Result<(Vec<Node>, usize, bool), (usize, String)> {
        self.at += 1;
        let mut items = Vec::new();
        let mut trailing = false;
        loop {
            self.skip();
            if self.peek() == Some(close) {
                let at = self.at;
                self.at += 1;
                return Ok((items, at, trailing));
            }
            items.push(self.value()?);
            self.skip();
            trailing = self.peek() == Some(b',');
            if trailing {
                self.at += 1;
            } else if self.peek() != Some(close) {
                return self.err(&format!("`,` or `{}`", close as char));
            }
        }
    }

    fn map(&mut self, start: usize) -> Result<Node, (usize, String)> {
        self.at += 1;
        let mut entries = Vec::new();
        let mut trailing = false;
        loop {
            self.skip();
            if self.peek() == Some(b'}') {
                let close = self.at;
                self.at += 1;
                return Ok(Node {
                    start,
                    end: self.at,
                    kind: Kind::Map(entries),
                    close,
                    trailing_comma: trailing,
                });
            }
            let key = self.value()?;
            self.skip();
            if self.peek() != Some(b':') {
                return self.err("`:` after a map key");
            }
            self.at += 1;
            let value = self.value()?;
            entries.push((key, value));
            self.skip();
            trailing = self.peek() == Some(b',');
            if trailing {
                self.at += 1;
            } else if self.peek() != Some(b'}') {
                return self.err("`,` or `}`");
            }
        }
    }

    /// After an optional name, at `(`: a struct if the first entry is `name:`, else a tuple.
    fn paren(&mut self, start: usize, name: Option<String>) -> Result<Node, (usize, String)> {
        let open = self.at;
        self.at += 1;
        self.skip();
        let is_struct = if self.peek() == Some(b')') {
            true
        } else if self.peek().is_some_and(Self::is_ident_start) {
            let back = self.at;
            self.ident();
            self.skip();
            let colon = self.peek() == Some(b':') && self.s.get(self.at + 1) != Some(&b':');
            self.at = back;
            colon
        } else {
            false
        };
        if !is_struct {
            self.at = open;
            let (items, close, trailing) = self.list(b')')?;
            return Ok(Node {
                start,
                end: self.at,
                kind: Kind::Tuple(name, items),
                close,
                trailing_comma: trailing,
            });
        }
        let mut fields = Vec::new();
        let mut trailing = false;
        loop {
            self.skip();
            if self.peek() == Some(b')') {
                let close = self.at;
                self.at += 1;
                return Ok(Node {
                    start,
                    end: self.at,
                    kind: Kind::Struct(fields),
                    close,
                    trailing_comma: trailing,
                });
            }
            if !self.peek().is_some_and(Self::is_ident_start) {
                return self.err("a field name");
            }
            let key = self.ident();
            self.skip();
            if self.peek() != Some(b':') {
                return self.err(&format!("`:` after the field name `{key}`"));
            }
            self.at += 1;
            let value = self.value()?;
            fields.push((key, value));
            self.skip();
            trailing = self.peek() == Some(b',');
            if trailing {
                self.at += 1;
            } else if self.peek() != Some(b')') {
                return self.err("`,` or `)`");
            }
        }
    }
}
