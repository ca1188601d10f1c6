//! Files and directories as every command makes them: one output directory helper, so that
//! `run`, `render`, `generate`, `cut`, `study` and the viewer say the same thing when a file
//! stands where a directory must go. Used by the front ends and the study alike, so it depends
//! on nothing of the crate.

use std::path::Path;

/// Creates `dir` and its parents, as [`std::fs::create_dir_all`] does, for every command that
/// writes into a directory it makes (`run`, `render`, `generate`, `cut`, `study`): where the
/// path or one of its parents is a file, the error says so ("a file of that name exists",
/// "x is a file, not a directory") instead of the system's "File exists (os error 17)" or
/// "Not a directory (os error 20)", which name neither the file nor the directory. The caller
/// puts `dir` and "cannot create the output directory" before it.
pub fn create_dir_clearly(dir: &Path) -> Result<(), String> {
    if dir.exists() && !dir.is_dir() {
        return Err("a file of that name exists".into());
    }
    if let Some(file) = dir
        .ancestors()
        .skip(1)
        .filter(|a| !a.as_os_str().is_empty())
        .find(|a| a.exists() && !a.is_dir())
    {
        return Err(format!("{} is a file, not a directory", file.display()));
    }
    std::fs::create_dir_all(dir).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::create_dir_clearly;

    #[test]
    fn a_file_in_the_way_is_named() {
        let dir = std::env::temp_dir().join(format!("dda3d-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("afile");
        std::fs::write(&file, "x").unwrap();
        assert_eq!(
            create_dir_clearly(&file),
            Err("a file of that name exists".into())
        );
        assert_eq!(
            create_dir_clearly(&file.join("a/b")),
            Err(format!("{} is a file, not a directory", file.display()))
        );
        create_dir_clearly(&dir.join("a/b")).unwrap();
        create_dir_clearly(&dir.join("a/b")).unwrap();
        assert!(dir.join("a/b").is_dir());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
