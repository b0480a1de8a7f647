//! Reading a whole file safely, for every file format the scene crate reads (glTF, ray and hit
//! files): only a regular file (not a device, pipe or folder), refused before reading when it
//! is larger than a limit. Each caller turns the fault into its own error type.

use std::path::Path;

/// Why a file was not read.
#[derive(Debug)]
pub(crate) enum ReadFault {
    Io(std::io::Error),
    NotAFile,
    TooLarge { len: u64 },
}

/// The bytes of the regular file `path`, at most `limit` of them.
pub(crate) fn read_regular_file(path: &Path, limit: u64) -> Result<Vec<u8>, ReadFault> {
    let meta = std::fs::metadata(path).map_err(ReadFault::Io)?;
    if !meta.is_file() {
        return Err(ReadFault::NotAFile);
    }
    if meta.len() > limit {
        return Err(ReadFault::TooLarge { len: meta.len() });
    }
    std::fs::read(path).map_err(ReadFault::Io)
}
