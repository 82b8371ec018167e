//! A fixed order for the attributes of a written OpenEXR header, so identical renders give
//! identical bytes (checksum-based caches and `cmp` work).
//!
//! A single-part OpenEXR file starts with the magic number and a version field (4 bytes
//! each), then the header: a sequence of attributes, each `name\0 type\0 size:i32le
//! value[size]`, ended by one NUL byte. The line-offset table that follows holds absolute
//! file positions, so reordering attributes inside the header, which keeps its length, leaves
//! the rest of the file valid. Attributes are sorted by name.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};

/// OpenEXR's magic number, little-endian.
const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
/// Version-field flag of multi-part files (which have several headers).
const MULTIPART_FLAG: u32 = 0x1000;
/// Longest header this reads back (the header of a 65536-pixel-tall image with every
/// attribute is far below this).
const MAX_HEADER_BYTES: u64 = 64 << 20;

/// One attribute's complete bytes and its name.
struct RawAttribute<'a> {
    name: &'a [u8],
    bytes: &'a [u8],
}

/// Returns the end offset of the NUL-terminated string starting at `at`.
fn string_end(data: &[u8], at: usize) -> Result<usize, String> {
    data[at..]
        .iter()
        .position(|&b| b == 0)
        .map(|n| at + n)
        .ok_or_else(|| "OpenEXR header ends inside an attribute name".to_string())
}

/// Sorts the header attributes of the single-part OpenEXR file in `data` by name, in place,
/// and returns where the header ends. `data` must hold at least the whole header.
pub fn sort_header_attributes(data: &mut [u8]) -> Result<usize, String> {
    if data.len() < 9 || data[..4] != MAGIC {
        return Err("not an OpenEXR file".into());
    }
    let version = u32::from_le_bytes([data[4], data[5], data[6], data[7]]);
    if version & MULTIPART_FLAG != 0 {
        return Err("cannot order the headers of a multi-part OpenEXR file".into());
    }
    let start = 8;
    let mut at = start;
    let mut attributes = Vec::new();
    loop {
        if at >= data.len() {
            return Err(TRUNCATED.into());
        }
        if data[at] == 0 {
            break;
        }
        let name_end = string_end(data, at)?;
        let type_end = string_end(data, name_end + 1)?;
        let size_at = type_end + 1;
        let size_bytes: [u8; 4] = data
            .get(size_at..size_at + 4)
            .and_then(|s| s.try_into().ok())
            .ok_or(TRUNCATED)?;
        let size = usize::try_from(i32::from_le_bytes(size_bytes))
            .map_err(|_| "OpenEXR attribute has a negative size")?;
        let end = size_at + 4 + size;
        if end > data.len() {
            return Err(TRUNCATED.into());
        }
        attributes.push((at, name_end, end));
        at = end;
    }
    let header = data[start..at].to_vec();
    let mut raw: Vec<RawAttribute> = attributes
        .iter()
        .map(|&(begin, name_end, end)| RawAttribute {
            name: &header[begin - start..name_end - start],
            bytes: &header[begin - start..end - start],
        })
        .collect();
    raw.sort_by(|a, b| a.name.cmp(b.name));
    let mut out = start;
    for attribute in raw {
        data[out..out + attribute.bytes.len()].copy_from_slice(attribute.bytes);
        out += attribute.bytes.len();
    }
    debug_assert_eq!(out, at);
    Ok(at + 1)
}

/// The message [`sort_header_attributes`] gives when `data` ends inside the header.
const TRUNCATED: &str = "OpenEXR header is truncated";

/// [`sort_header_attributes`] on a file just written (readable and writable): reads as much
/// of the file's start as the header needs and writes back only the header.
pub fn sort_header_attributes_in_file(file: &mut File) -> Result<(), String> {
    let io = |e: std::io::Error| format!("cannot reorder the OpenEXR header: {e}");
    let file_length = file.metadata().map_err(io)?.len();
    let mut length = (64u64 << 10).min(file_length);
    loop {
        let mut data = vec![0u8; length as usize];
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        file.read_exact(&mut data).map_err(io)?;
        match sort_header_attributes(&mut data) {
            Ok(header_end) => {
                file.seek(SeekFrom::Start(0)).map_err(io)?;
                file.write_all(&data[..header_end]).map_err(io)?;
                file.seek(SeekFrom::End(0)).map_err(io)?;
                return Ok(());
            }
            Err(message) if message == TRUNCATED && length < file_length.min(MAX_HEADER_BYTES) => {
                length = (length * 4).min(file_length).min(MAX_HEADER_BYTES);
            }
            Err(message) => return Err(message),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attribute(name: &str, kind: &str, value: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(name.as_bytes());
        out.push(0);
        out.extend_from_slice(kind.as_bytes());
        out.push(0);
        out.extend_from_slice(&(value.len() as i32).to_le_bytes());
        out.extend_from_slice(value);
        out
    }

    fn file(attributes: &[Vec<u8>], tail: &[u8]) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&2u32.to_le_bytes());
        for a in attributes {
            out.extend_from_slice(a);
        }
        out.push(0);
        out.extend_from_slice(tail);
        out
    }

    #[test]
    fn attributes_come_out_sorted_and_the_rest_untouched() {
        let b = attribute("channels", "chlist", &[1, 2, 3]);
        let a = attribute("zebra", "int", &7i32.to_le_bytes());
        let c = attribute("compression", "compression", &[3]);
        let mut data = file(&[a.clone(), b.clone(), c.clone()], b"offsets and pixels");
        sort_header_attributes(&mut data).unwrap();
        assert_eq!(data, file(&[b, c, a], b"offsets and pixels"));
    }

    #[test]
    fn malformed_headers_are_refused() {
        let mut truncated = file(&[attribute("a", "int", &[0; 4])], b"");
        truncated.truncate(truncated.len() - 3);
        assert!(sort_header_attributes(&mut truncated).is_err());
        assert!(sort_header_attributes(&mut b"not exr at all".to_vec()).is_err());
        let mut multipart = file(&[], b"");
        multipart[4..8].copy_from_slice(&(2u32 | MULTIPART_FLAG).to_le_bytes());
        assert!(sort_header_attributes(&mut multipart).is_err());
    }
}
