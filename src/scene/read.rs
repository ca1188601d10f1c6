//! A scene file's bytes, read no further than [`MAX_FILE_BYTES`]: a device or a pipe that never
//! ends (`/dev/zero`) is refused at the limit instead of filling the memory.

use std::fmt;
use std::io::Read;
use std::path::Path;

use super::MAX_FILE_BYTES;
use crate::text::short;

/// Why [`read_utf8`] read nothing: the file could not be read, it is (or goes on) beyond the
/// limit (the message says how far), or it is not UTF-8 (the line of the first bad byte).
#[derive(Debug)]
pub(crate) enum ReadError {
    Io(std::io::Error),
    TooLarge(String),
    NotUtf8 { line: usize, message: String },
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReadError::Io(e) => write!(f, "cannot read: {e}"),
            ReadError::TooLarge(m) => f.write_str(m),
            ReadError::NotUtf8 { line, message } => write!(f, "line {line}: {message}"),
        }
    }
}

/// The file's bytes, at most [`MAX_FILE_BYTES`] of them. A regular file says its size up front;
/// a device, pipe or terminal (`/dev/zero`) does not, and is read up to the limit. `kind` names
/// the file in the message ("a scene file").
fn read_bounded(path: &Path, kind: &str) -> Result<Vec<u8>, ReadError> {
    let file = std::fs::File::open(path).map_err(ReadError::Io)?;
    let too_large = |size: &str| {
        ReadError::TooLarge(format!(
            "{size}, more than the limit of {} MiB for {kind}",
            MAX_FILE_BYTES >> 20
        ))
    };
    if let Ok(meta) = file.metadata()
        && meta.is_file()
        && meta.len() > MAX_FILE_BYTES
    {
        // In MiB, short, unless that rounds to the limit itself.
        let mib = short(meta.len() as f64 / f64::from(1 << 20));
        let size = if mib
            .parse()
            .is_ok_and(|m: f64| m * f64::from(1 << 20) > MAX_FILE_BYTES as f64)
        {
            format!("{mib} MiB")
        } else {
            format!("{} bytes", meta.len())
        };
        return Err(too_large(&format!("the file is {size}")));
    }
    let mut bytes = Vec::new();
    file.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(ReadError::Io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(too_large("the input goes on"));
    }
    Ok(bytes)
}

/// The file's text ([`read_bounded`]'s bytes), which must be UTF-8: `kind` is TOML ("a scene
/// file", "a study file").
pub(crate) fn read_utf8(path: &Path, kind: &str) -> Result<String, ReadError> {
    String::from_utf8(read_bounded(path, kind)?).map_err(|e| {
        let bytes = e.as_bytes();
        let bad = e.utf8_error().valid_up_to();
        let line_start = bytes[..bad]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |k| k + 1);
        ReadError::NotUtf8 {
            line: bytes[..bad].iter().filter(|&&b| b == b'\n').count() + 1,
            message: format!(
                "not UTF-8 text: byte 0x{:02x} at column {} ({kind} is TOML, which is UTF-8)",
                bytes[bad],
                bad - line_start + 1
            ),
        }
    })
}
