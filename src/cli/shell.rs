//! Paths in the commands that runs record (a PNG's text, a CSV's first line, a film's
//! comment), written so that a shell reads each back as the one path it is.

/// A path as one word a shell reads back as that path: as it is where every character is
/// plain, else in single quotes (a quote as '\\''), or as bash's $'...' where it holds a
/// control character (a newline would end a recorded command's line); a relative path that
/// begins with `-` behind `./`, so that it is never read as a flag.
pub fn word(path: &std::path::Path) -> String {
    let text = path.to_string_lossy();
    let text = match text.starts_with('-') {
        true => format!("./{text}"),
        false => text.into_owned(),
    };
    let plain = |c: char| c.is_ascii_alphanumeric() || "_./,:=+@%-".contains(c);
    if !text.is_empty() && text.chars().all(plain) {
        return text;
    }
    if text.chars().any(char::is_control) {
        let mut out = String::from("$'");
        for c in text.chars() {
            match c {
                '\\' => out += "\\\\",
                '\'' => out += "\\'",
                '\n' => out += "\\n",
                '\t' => out += "\\t",
                '\r' => out += "\\r",
                c if c.is_control() => out += &format!("\\x{:02x}", c as u32),
                c => out.push(c),
            }
        }
        return out + "'";
    }
    format!("'{}'", text.replace('\'', "'\\''"))
}

#[cfg(test)]
mod tests {
    use super::word;
    use std::path::Path;

    /// Each name comes back whole from bash (`printf %s WORD`), and no word holds a line
    /// break.
    #[test]
    fn a_path_is_one_shell_word() {
        for name in [
            "plain/film.mp4",
            "with space.mp4",
            "it's.mp4",
            "new\nline.mp4",
            "-report",
            "concat:a.mp4|b.mp4",
            "ünï 映画.mp4",
            "$(touch x)`y`.mp4",
        ] {
            let w = word(Path::new(name));
            assert!(!w.contains('\n'), "{w}");
            let o = std::process::Command::new("bash")
                .args(["-c", &format!("printf %s {w}")])
                .output()
                .unwrap();
            let back = String::from_utf8(o.stdout).unwrap();
            let want = match name.starts_with('-') {
                true => format!("./{name}"),
                false => name.to_string(),
            };
            assert_eq!(back, want, "{w}");
        }
    }
}
