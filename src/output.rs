//! Files written whole or not at all: each is written to a temporary file beside it and renamed
//! into place, so a crash, a full disk or an interrupted render never leaves a half-written file
//! under the real name, and a failed write leaves no temporary file behind.

use std::path::{Path, PathBuf};

/// The temporary file `path` is written through (`NAME.tmp` beside it).
pub fn temporary_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    path.with_file_name(name)
}

/// Writes `path` by calling `write` on its temporary file, then renaming it into place. On any
/// failure the temporary file is removed and `path` is left as it was.
pub fn write_whole(path: &Path, write: impl FnOnce(&Path) -> Result<(), String>) -> Result<(), String> {
    let temporary = temporary_path(path);
    let result = write(&temporary).and_then(|()| {
        std::fs::rename(&temporary, path)
            .map_err(|e| format!("cannot rename {} to {}: {e}", temporary.display(), path.display()))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_keeps_the_old_file_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("caustic-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("frame_0001.exr");
        write_whole(&path, |t| std::fs::write(t, "old").map_err(|e| e.to_string())).unwrap();
        let failed = write_whole(&path, |t| {
            std::fs::write(t, "half").unwrap();
            Err("the disk is full".into())
        });
        assert_eq!(failed, Err("the disk is full".into()));
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert!(!temporary_path(&path).exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
