//! OBJ and MTL files as exporters write them, turned into text `tobj` can read, with the
//! line number of whatever `tobj` then refuses.
//!
//! `tobj` reads its input with `BufRead::lines`, which fails on the first line that is not
//! UTF-8; the whole file (or the whole MTL library) is then lost to a bare "read error".
//! Exporters of the Latin-1 era (3ds Max's Max2Obj among them) write names such as
//! `Terraind\xE6k` as single bytes. [`decode_lines`] therefore decodes every line on its own:
//! as UTF-8 when it is valid UTF-8, otherwise byte by byte as Latin-1 (each byte becomes the
//! code point of the same value), which never fails and never merges two different byte
//! strings. Both the OBJ and its MTL go through the same decoding, so `usemtl` and `newmtl`
//! names still match; a name written as UTF-8 in one file and as Latin-1 in the other even
//! decodes to the same text. Files that start with a UTF-16 byte-order mark are decoded as
//! UTF-16, and a UTF-8 byte-order mark is dropped (otherwise `tobj` would read the first
//! line's keyword as `\u{feff}v` and silently skip it).
//!
//! `tobj`'s errors carry no position. [`LineCountingReader`] hands `tobj` the text and counts
//! the lines it has taken: `tobj` stops at the first line it cannot parse, so the count at
//! that moment is the offending line.

use std::io::{BufRead, Read};

/// The lines of an OBJ or MTL file, decoded leniently (see the module documentation), without
/// their line terminators (`\n` or `\r\n`). Line `i` of the result is line `i + 1` of the file.
pub(crate) fn decode_lines(bytes: &[u8]) -> Vec<String> {
    if let Some(text) = decode_utf16_with_bom(bytes) {
        return text
            .split('\n')
            .map(|line| line.strip_suffix('\r').unwrap_or(line).to_owned())
            .collect();
    }
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    bytes
        .split(|&b| b == b'\n')
        .map(|line| decode_line(line.strip_suffix(b"\r").unwrap_or(line)))
        .collect()
}

/// Joins lines continued with a trailing backslash (the OBJ specification's line
/// continuation, `f 1 2 \\` then `3 4`) into the first of them, leaving the lines it took
/// empty: every line keeps its number, and an error in a continued statement names the line
/// it starts on.
pub(crate) fn join_continued_lines(lines: &mut [String]) {
    let mut start = 0;
    while start < lines.len() {
        let mut next = start + 1;
        while lines[start].trim_end().ends_with('\\') && next < lines.len() {
            let kept = lines[start].trim_end().trim_end_matches('\\').to_owned();
            let taken = std::mem::take(&mut lines[next]);
            lines[start] = format!("{kept} {taken}");
            next += 1;
        }
        start = next;
    }
}

/// One line as UTF-8 when valid, else as Latin-1 (byte value = code point).
fn decode_line(line: &[u8]) -> String {
    match std::str::from_utf8(line) {
        Ok(text) => text.to_owned(),
        Err(_) => line.iter().map(|&b| char::from(b)).collect(),
    }
}

/// The text of a file that starts with a UTF-16 byte-order mark (unpaired surrogates become
/// U+FFFD), or `None` without one.
fn decode_utf16_with_bom(bytes: &[u8]) -> Option<String> {
    let big_endian = match bytes {
        [0xFE, 0xFF, ..] => true,
        [0xFF, 0xFE, ..] => false,
        _ => return None,
    };
    let units = bytes[2..].chunks_exact(2).map(|pair| {
        if big_endian {
            u16::from_be_bytes([pair[0], pair[1]])
        } else {
            u16::from_le_bytes([pair[0], pair[1]])
        }
    });
    Some(
        char::decode_utf16(units)
            .map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER))
            .collect(),
    )
}

/// A reader over text that knows which line its consumer is on: after the consumer has taken
/// some bytes, [`LineCountingReader::line`] is the 1-based number of the line the last byte
/// taken belongs to (0 before anything is taken).
pub(crate) struct LineCountingReader<'a> {
    rest: &'a [u8],
    line: usize,
    at_line_start: bool,
}

impl<'a> LineCountingReader<'a> {
    pub(crate) fn new(text: &'a str) -> Self {
        LineCountingReader {
            rest: text.as_bytes(),
            line: 0,
            at_line_start: true,
        }
    }

    /// The line the consumer last read from.
    pub(crate) fn line(&self) -> usize {
        self.line
    }

    fn count(&mut self, taken: &[u8]) {
        for &b in taken {
            if self.at_line_start {
                self.line += 1;
                self.at_line_start = false;
            }
            if b == b'\n' {
                self.at_line_start = true;
            }
        }
    }
}

impl Read for LineCountingReader<'_> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let n = out.len().min(self.rest.len());
        out[..n].copy_from_slice(&self.rest[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for LineCountingReader<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(self.rest)
    }

    fn consume(&mut self, amount: usize) {
        let amount = amount.min(self.rest.len());
        let (taken, rest) = self.rest.split_at(amount);
        self.count(taken);
        self.rest = rest;
    }
}

/// `line` shortened to at most `max_chars` characters for an error message.
pub(crate) fn excerpt(line: &str, max_chars: usize) -> String {
    let line = line.trim();
    if line.chars().count() <= max_chars {
        line.to_owned()
    } else {
        let mut short: String = line.chars().take(max_chars).collect();
        short.push_str("...");
        short
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latin1_lines_decode_byte_for_byte_and_utf8_lines_stay_utf8() {
        let lines = decode_lines(b"usemtl Terraind\xE6k\r\nnewmtl Terraind\xC3\xA6k\nlast");
        assert_eq!(
            lines,
            ["usemtl Terraind\u{e6}k", "newmtl Terraind\u{e6}k", "last"]
        );
        // Two different invalid byte strings stay different.
        assert_ne!(decode_lines(b"\xE6\xFF"), decode_lines(b"\xE6\xFE"));
    }

    #[test]
    fn byte_order_marks_are_honoured() {
        assert_eq!(decode_lines(b"\xEF\xBB\xBFv 1 2 3\n"), ["v 1 2 3", ""]);
    }

    /// `\\` at the end of a line continues the statement on the next one; the lines keep
    /// their numbers. Such files were refused ("face parse error").
    #[test]
    fn continued_lines_are_joined_in_place() {
        let mut lines: Vec<String> = ["v -1 \\", "  -1 0", "f 1/1 2/2 \\", "3/3 \\", "4/4", "g x"]
            .iter()
            .map(|l| l.to_string())
            .collect();
        join_continued_lines(&mut lines);
        assert_eq!(
            lines,
            ["v -1    -1 0", "", "f 1/1 2/2  3/3  4/4", "", "", "g x"]
        );
        let utf16be: Vec<u8> = [0xFE, 0xFF]
            .into_iter()
            .chain("v 1\r\nf 1".encode_utf16().flat_map(u16::to_be_bytes))
            .collect();
        assert_eq!(decode_lines(&utf16be), ["v 1", "f 1"]);
        let utf16le: Vec<u8> = [0xFF, 0xFE]
            .into_iter()
            .chain("g \u{e6}".encode_utf16().flat_map(u16::to_le_bytes))
            .collect();
        assert_eq!(decode_lines(&utf16le), ["g \u{e6}"]);
    }

    #[test]
    fn the_reader_reports_the_line_being_read() {
        let mut reader = LineCountingReader::new("a\nbb\n\nccc");
        let mut lines = Vec::new();
        for line in (&mut reader).lines() {
            lines.push(line.unwrap());
            if lines.len() == 2 {
                break;
            }
        }
        assert_eq!(reader.line(), 2);
        let rest: Vec<String> = (&mut reader).lines().map(Result::unwrap).collect();
        assert_eq!(rest, ["", "ccc"]);
        assert_eq!(reader.line(), 4);
    }
}
