//! A scene file's bytes, read no further than [`MAX_FILE_BYTES`]: a device or a pipe that never
//! ends (`/dev/zero`) is refused at the limit instead of filling the memory.

use std::fmt;
use std::io::Read;
use std::path::Path;

use super::MAX_FILE_BYTES;
use crate::text::short;

/// Why [`read_bounded`] read nothing: the file could not be read, or it is (or goes on)
/// beyond the limit (the message says how far).
#[derive(Debug)]
pub(crate) enum ReadError {
    Io(std::io::Error),
    TooLarge(String),
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReadError::Io(e) => write!(f, "cannot read: {e}"),
            ReadError::TooLarge(m) => f.write_str(m),
        }
    }
}

/// The file's bytes, at most [`MAX_FILE_BYTES`] of them. A regular file says its size up front;
/// a device, pipe or terminal (`/dev/zero`) does not, and is read up to the limit. `kind` names
/// the file in the message ("a scene file").
pub(crate) fn read_bounded(path: &Path, kind: &str) -> Result<Vec<u8>, ReadError> {
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
