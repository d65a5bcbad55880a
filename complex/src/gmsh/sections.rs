//! Reading the raw sections of a `.msh` file that the parser does not
//! check or report well: the format line, section headers (counts and tag
//! ranges), node tags and physical names, and the location of a parse
//! error.

use super::{parse_error, GmshError, REEXPORT};
use mshio::MshParserError;
use std::collections::HashMap;
use std::path::Path;

/// The `$MeshFormat` line: encoding of the numbers that follow.
#[derive(Clone, Copy, Debug)]
pub(super) struct Format {
    binary: bool,
    big_endian: bool,
    size_t: usize,
}

/// Check the `$MeshFormat` section: version 4.1, ASCII or binary, and a
/// `size_t` width the parser handles.
pub(super) fn read_format(bytes: &[u8], path: &Path) -> Result<Format, GmshError> {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    let rest = &bytes[start..];
    let rest = rest.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(rest);
    let not_msh = || {
        parse_error(
            path,
            "it does not start with `$MeshFormat`, so it is not a Gmsh mesh file; a geometry script (.geo) must be meshed first, e.g. `gmsh -2 model.geo -o model.msh` (or `-3` for a volume mesh)",
        )
    };
    let Some(body) = rest.strip_prefix(b"$MeshFormat") else {
        return Err(not_msh());
    };
    let skip = body
        .iter()
        .take_while(|&&b| b == b'\r' || b == b'\n')
        .count();
    let Some(line_end) = body[skip..]
        .iter()
        .position(|&b| b == b'\n')
        .map(|p| skip + p)
    else {
        return Err(parse_error(
            path,
            format!("the $MeshFormat section ends early; the file is truncated: {REEXPORT}"),
        ));
    };
    let line = String::from_utf8_lossy(&body[skip..line_end]);
    let fields: Vec<&str> = line.split_whitespace().collect();
    let Some(&version) = fields.first() else {
        return Err(not_msh());
    };
    if version.parse::<f64>().ok() != Some(4.1) {
        return Err(GmshError::UnsupportedVersion {
            path: path.to_path_buf(),
            found: version.to_string(),
        });
    }
    let binary = match fields.get(1) {
        Some(&"0") => false,
        Some(&"1") => true,
        other => {
            return Err(parse_error(
                path,
                format!(
                "the file type in $MeshFormat is {}, expected 0 (ASCII) or 1 (binary): {REEXPORT}",
                other.unwrap_or(&"missing")
            ),
            ))
        }
    };
    let size_t = match fields.get(2).and_then(|s| s.parse::<usize>().ok()) {
        Some(s @ (4 | 8)) => s,
        _ => {
            return Err(parse_error(
                path,
                format!(
                    "the data size in $MeshFormat must be 4 or 8 (bytes of size_t): {REEXPORT}"
                ),
            ))
        }
    };
    let mut big_endian = false;
    if binary {
        let after = &body[line_end + 1..];
        let one: Option<[u8; 4]> = after.get(..4).and_then(|b| b.try_into().ok());
        match one {
            Some(b) if i32::from_le_bytes(b) == 1 => {}
            Some(b) if i32::from_be_bytes(b) == 1 => big_endian = true,
            _ => {
                return Err(parse_error(
                    path,
                    format!("the binary $MeshFormat section lacks the endianness marker (the integer 1): {REEXPORT}"),
                ))
            }
        }
    }
    Ok(Format {
        binary,
        big_endian,
        size_t,
    })
}

/// Turn mshio's error backtrace into one line: what failed, where, and a hint.
pub(super) fn describe_parse_error(bytes: &[u8], error: &MshParserError<&[u8]>) -> String {
    let chain: Vec<&(&[u8], mshio::error::MshParserErrorKind)> =
        error.filter_msh_errors().collect();
    let Some((rest, kind)) = chain.first() else {
        return format!("the file could not be parsed; {REEXPORT}");
    };
    let offset = bytes.len().saturating_sub(rest.len());
    let line = bytes[..offset].iter().filter(|&&b| b == b'\n').count() + 1;
    let context: Vec<String> = chain[1..]
        .iter()
        .rev()
        .map(|(_, k)| k.context().map_or_else(|| k.to_string(), str::to_string))
        .collect();
    let truncated = !rest.windows(4).any(|w| w == b"$End");
    let hint = if truncated {
        format!("the file ends before its last section is complete, so it was probably truncated while being written or copied; {REEXPORT}")
    } else {
        format!("check the file against the MSH 4.1 format, or {REEXPORT}")
    };
    format!(
        "{kind} (near line {line}, byte {offset}; while reading {}); {hint}",
        if context.is_empty() {
            "the file".to_string()
        } else {
            context.join(" > ")
        }
    )
}

/// Position just after the line `name` (at the start of a line).
fn find_section(bytes: &[u8], name: &str) -> Option<usize> {
    find_line(bytes, name).map(|(_, body)| body)
}

/// Start of the line `name` and start of the line after it.
fn find_line(bytes: &[u8], name: &str) -> Option<(usize, usize)> {
    let pat = name.as_bytes();
    let mut from = 0;
    while let Some(p) = bytes.get(from..)?.windows(pat.len()).position(|w| w == pat) {
        let at = from + p;
        let end = at + pat.len();
        let line_start = at == 0 || bytes[at - 1] == b'\n';
        let after = &bytes[end..];
        let eol = if after.starts_with(b"\r\n") {
            Some(2)
        } else if after.starts_with(b"\n") {
            Some(1)
        } else {
            None
        };
        if let (true, Some(k)) = (line_start, eol) {
            return Some((at, end + k));
        }
        from = at + 1;
    }
    None
}

/// Reads the numbers of a section in either encoding.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: Format,
}

impl<'a> Reader<'a> {
    fn at(bytes: &'a [u8], format: Format, section: &str) -> Option<Self> {
        Some(Self {
            bytes,
            pos: find_section(bytes, section)?,
            format,
        })
    }

    fn token(&mut self) -> Option<&'a str> {
        let rest = self.bytes.get(self.pos..)?;
        let start = rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let len = rest[start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len() - start);
        self.pos += start + len;
        std::str::from_utf8(&rest[start..start + len]).ok()
    }

    fn raw(&mut self, width: usize) -> Option<&'a [u8]> {
        let b = self.bytes.get(self.pos..self.pos + width)?;
        self.pos += width;
        Some(b)
    }

    fn unsigned(&mut self, width: usize) -> Option<u64> {
        let b = self.raw(width)?;
        let mut value = 0u64;
        for k in 0..width {
            let byte = if self.format.big_endian {
                b[k]
            } else {
                b[width - 1 - k]
            };
            value = (value << 8) | u64::from(byte);
        }
        Some(value)
    }

    fn size_t(&mut self) -> Option<u64> {
        if self.format.binary {
            self.unsigned(self.format.size_t)
        } else {
            self.token()?.parse().ok()
        }
    }

    fn int(&mut self) -> Option<i64> {
        if self.format.binary {
            // Two's complement of a 32-bit int.
            self.unsigned(4).map(|v| i64::from(v as u32 as i32))
        } else {
            self.token()?.parse().ok()
        }
    }

    fn skip_doubles(&mut self, count: usize) -> Option<()> {
        if self.format.binary {
            self.raw(count.checked_mul(8)?).map(|_| ())
        } else {
            for _ in 0..count {
                self.token()?;
            }
            Some(())
        }
    }
}

/// The four numbers heading each `$Nodes` or `$Elements` line of the file:
/// blocks, count, smallest tag, largest tag.
pub(super) fn section_headers(bytes: &[u8], format: Format, section: &str) -> Vec<[u64; 4]> {
    let mut headers = Vec::new();
    let mut from = 0;
    while let Some((line, body)) = bytes.get(from..).and_then(|rest| find_line(rest, section)) {
        let mut r = Reader {
            bytes,
            pos: from + body,
            format,
        };
        if let (Some(a), Some(b), Some(c), Some(d)) =
            (r.size_t(), r.size_t(), r.size_t(), r.size_t())
        {
            headers.push([a, b, c, d]);
        }
        from += line + 1;
    }
    headers
}

/// Node tags in file order, read from the `$Nodes` section directly (mshio
/// drops them when they are consecutive, even if the blocks list them out of
/// order). `None` if the section does not have the expected layout.
pub(super) fn scan_node_tags(bytes: &[u8], format: Format) -> Option<Vec<u64>> {
    let mut r = Reader::at(bytes, format, "$Nodes")?;
    let blocks = r.size_t()?;
    let total = r.size_t()?;
    r.size_t()?;
    r.size_t()?;
    let mut tags = Vec::with_capacity(usize::try_from(total).ok()?.min(bytes.len()));
    for _ in 0..blocks {
        r.int()?;
        r.int()?;
        if r.int()? != 0 {
            return None; // parametric nodes: mshio refuses them anyway
        }
        let count = usize::try_from(r.size_t()?).ok()?;
        if count > bytes.len() {
            return None;
        }
        for _ in 0..count {
            tags.push(r.size_t()?);
        }
        r.skip_doubles(count.checked_mul(3)?)?;
    }
    (tags.len() as u64 == total).then_some(tags)
}

/// The `$PhysicalNames` section (plain text in ASCII and binary files):
/// (dimension, tag) → name.
pub(super) fn physical_names(
    bytes: &[u8],
    path: &Path,
) -> Result<HashMap<(i32, i32), String>, GmshError> {
    let mut names = HashMap::new();
    let Some(start) = find_section(bytes, "$PhysicalNames") else {
        return Ok(names);
    };
    let first_line = bytes[..start].iter().filter(|&&b| b == b'\n').count() + 1;
    let end = find_line(&bytes[start..], "$EndPhysicalNames")
        .map(|(line, _)| start + line)
        .ok_or_else(|| {
            parse_error(
                path,
                format!("the $PhysicalNames section has no `$EndPhysicalNames`; the file is truncated: {REEXPORT}"),
            )
        })?;
    let text = String::from_utf8_lossy(&bytes[start..end]);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (first_line + i, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let bad = |line: usize, what: &str| {
        parse_error(
            path,
            format!("line {line}: {what} in $PhysicalNames (expected `dim tag \"name\"` lines after their count)"),
        )
    };
    let count: usize = match lines.next() {
        Some((line, l)) => l
            .parse()
            .map_err(|_| bad(line, "the count is not a number"))?,
        None => return Ok(names),
    };
    let mut seen = 0;
    for (line, l) in lines {
        let mut fields = l.splitn(3, char::is_whitespace);
        let dim = fields.next().and_then(|s| s.parse::<i32>().ok());
        let tag = fields.next().and_then(|s| s.parse::<i32>().ok());
        let (Some(dim), Some(tag)) = (dim, tag) else {
            return Err(bad(line, "the dimension or tag is not a number"));
        };
        let name = fields.next().unwrap_or("").trim();
        let name = name
            .strip_prefix('"')
            .and_then(|s| s.strip_suffix('"'))
            .unwrap_or(name);
        if name.is_empty() {
            return Err(bad(line, "the name is empty"));
        }
        names.insert((dim, tag), name.to_string());
        seen += 1;
    }
    if seen != count {
        return Err(parse_error(
            path,
            format!("line {first_line}: $PhysicalNames announces {count} names but lists {seen}"),
        ));
    }
    Ok(names)
}
