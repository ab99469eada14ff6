//! Lines into commands: `&` continuation, `#` comments, LAMMPS quoting, and the file loop
//! (with `jump SELF LABEL`, which rereads the file from its label).

use super::*;

/// Splits a command line into words; a quoted string ("…" or '…') is one word (quotes removed).
pub(super) fn words(line: &str) -> R<Vec<String>> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quotes = Quotes::default();
    let mut had = false;
    for c in line.chars() {
        if quotes.mark(c) {
            had = true;
        } else if !quotes.open() && c.is_whitespace() {
            if had || !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
                had = false;
            }
        } else {
            cur.push(c);
        }
    }
    if let Some(q) = quotes.0 {
        return Err(format!("unterminated quote {q}"));
    }
    if had || !cur.is_empty() {
        out.push(cur);
    }
    Ok(out)
}

/// Strips a `#` comment that is not inside quotes.
pub(super) fn strip_comment(line: &str) -> &str {
    let mut quotes = Quotes::default();
    for (k, c) in line.char_indices() {
        if !quotes.mark(c) && !quotes.open() && c == '#' {
            return &line[..k];
        }
    }
    line
}

/// LAMMPS quoting: "…" or '…' enclose text; inside one kind, the other is a plain character.
#[derive(Default)]
pub(super) struct Quotes(Option<char>);

impl Quotes {
    /// Feeds one character; true if it is a quote mark that opened or closed a quote.
    pub(super) fn mark(&mut self, c: char) -> bool {
        match self.0 {
            Some(q) if c == q => self.0 = None,
            None if c == '"' || c == '\'' => self.0 = Some(c),
            _ => return false,
        }
        true
    }

    pub(super) fn open(&self) -> bool {
        self.0.is_some()
    }
}

impl Deck {
    pub(super) fn execute(&mut self, text: &str, path: &Path) -> R<()> {
        let fname = path.display().to_string();
        let outer = std::mem::replace(&mut self.file, fname.clone());
        let r = self.execute_lines(text, &fname);
        self.file = outer;
        r
    }

    fn execute_lines(&mut self, text: &str, fname: &str) -> R<()> {
        if let Some((line, what)) = scope::out_of_scope(text) {
            return Err(format!("{fname}:{line}: {what}"));
        }
        let lines: Vec<&str> = text.lines().collect();
        let mut k = 0;
        while k < lines.len() {
            let start = k;
            let mut line = String::new();
            // '&' at the end of a line continues the command on the next line.
            loop {
                let l = lines[k].trim_end();
                k += 1;
                if let Some(stripped) = l.strip_suffix('&') {
                    line.push_str(stripped);
                    line.push(' ');
                    if k < lines.len() {
                        continue;
                    }
                } else {
                    line.push_str(l);
                }
                break;
            }
            self.line_no = start + 1;
            let cmd = strip_comment(&line).trim().to_string();
            self.logln(&line);
            if cmd.is_empty() {
                continue;
            }
            self.command(&cmd).map_err(|e| format!("{fname}:{}: {e}", start + 1))?;
            if let Some(label) = self.pending_jump.take() {
                // LAMMPS rereads the file from its start up to the label (none: from the start).
                k = if label.is_empty() {
                    0
                } else {
                    let at = lines.iter().position(|l| {
                        let w: Vec<&str> = strip_comment(l).split_whitespace().collect();
                        w.len() == 2 && w[0] == "label" && w[1] == label
                    });
                    at.ok_or_else(|| format!("{fname}:{}: jump: no label {label} in this file", start + 1))?
                        + 1
                };
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{strip_comment, words};

    /// LAMMPS quoting: double or single quotes make one word, the other kind is plain inside,
    /// and `#` inside quotes is not a comment.
    #[test]
    fn quotes_of_either_kind_make_one_word() {
        let w = words(r#"if "${a} > 0" then "dump_modify d format '%d %g'" 'x "y"'"#).unwrap();
        assert_eq!(w, ["if", "${a} > 0", "then", "dump_modify d format '%d %g'", "x \"y\""]);
        assert_eq!(words("print ''").unwrap(), ["print", ""]);
        assert!(words("print 'open").unwrap_err().contains("unterminated quote '"));
        assert_eq!(strip_comment("print '# not a comment' # a comment"), "print '# not a comment' ");
        assert_eq!(strip_comment(r#"print "it's" # c"#), r#"print "it's" "#);
    }
}
