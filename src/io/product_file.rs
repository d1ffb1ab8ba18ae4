//! Writing a file of results without following a symbolic link. A link under the name of a
//! result points at something of the user's (their own data, a file elsewhere), which a run
//! must never overwrite: opening the name fails instead, saying where the link points. This
//! holds for a link made before the run and for one made while it runs, since the check is
//! the operating system's own (`O_NOFOLLOW`), made as the file is opened. A file replaced in
//! one step is written to `NAME.tmp`, created afresh (never an existing file or link of that
//! name), then renamed over `NAME`.

use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// A symbolic link where a result is to be written.
#[derive(Debug, thiserror::Error)]
#[error(
    "a symbolic link to {} is {place}, and results are never written through a link: remove \
     the link or choose another output folder",
    target.display()
)]
pub struct LinkInTheWay {
    pub target: PathBuf,
    /// Where, said of the file: `in its place`, or in that of its temporary file.
    pub place: String,
}

/// The link at `path`, if `path` is one.
pub fn link_at(path: &Path) -> Option<LinkInTheWay> {
    let meta = std::fs::symlink_metadata(path).ok()?;
    if !meta.file_type().is_symlink() {
        return None;
    }
    let target = std::fs::read_link(path).unwrap_or_else(|_| PathBuf::from("?"));
    Some(LinkInTheWay {
        target,
        place: "in its place".into(),
    })
}

/// Opens `path` with `options` unless it is a symbolic link; a link is the error
/// [`LinkInTheWay`] (inside the `io::Error`), naming where it points.
pub fn open(path: &Path, options: &mut OpenOptions) -> io::Result<File> {
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(options, libc::O_NOFOLLOW);
    // elsewhere the check before opening is all there is
    #[cfg(not(unix))]
    refuse_link(path)?;
    options.open(path).map_err(|e| match link_at(path) {
        Some(link) => io::Error::new(io::ErrorKind::AlreadyExists, link),
        None => e,
    })
}

/// Creates `path`, or empties it, for writing.
pub fn create(path: &Path) -> io::Result<File> {
    open(
        path,
        OpenOptions::new().write(true).create(true).truncate(true),
    )
}

/// Opens `path` to add to its end, creating it if missing.
pub fn append(path: &Path) -> io::Result<File> {
    open(path, OpenOptions::new().append(true).create(true))
}

/// Writes `bytes` to `path`, created or emptied.
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    create(path)?.write_all(bytes)
}

/// Replaces `path` with `bytes` in one step, through `path.tmp` and a rename, so that a reader
/// (or a run killed at any instant) never finds it half-written. A link at `path` is refused
/// too: the rename would replace the user's link. A write that fails removes its temporary
/// file.
pub fn replace(path: &Path, bytes: &[u8]) -> io::Result<()> {
    refuse_link(path)?;
    let tmp = tmp_path(path);
    remove_stale(&tmp)?;
    let written = open(&tmp, OpenOptions::new().write(true).create_new(true))
        .and_then(|mut file| file.write_all(bytes));
    if let Err(e) = written {
        // a disk that filled up mid-write leaves a partial temporary file: not ours to leave
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// `path.tmp`, the name a file replaced in one step is written under first.
pub fn tmp_path(path: &Path) -> PathBuf {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    PathBuf::from(tmp)
}

/// A regular `.tmp` file left by a run killed mid-write (by a command that does not clear its
/// folder first) is removed; a link of that name is refused.
fn remove_stale(tmp: &Path) -> io::Result<()> {
    if let Some(mut link) = link_at(tmp) {
        let name = tmp.file_name().unwrap_or_default().to_string_lossy();
        link.place = format!("in the place of its temporary file {name}");
        return Err(io::Error::new(io::ErrorKind::AlreadyExists, link));
    }
    match std::fs::remove_file(tmp) {
        Err(e) if e.kind() != io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

fn refuse_link(path: &Path) -> io::Result<()> {
    match link_at(path) {
        Some(link) => Err(io::Error::new(io::ErrorKind::AlreadyExists, link)),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "thermostamp-product-file-{name}-{}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A link put in a result's place (here after any folder check, as a link made while a
    /// run goes would be) is refused by every way of writing, its target untouched, and the
    /// error names the target.
    #[test]
    fn a_link_in_a_results_place_is_never_written_through() {
        let dir = folder("link");
        let mine = dir.join("mine.csv");
        std::fs::write(&mine, "the user's data\n").unwrap();
        let result = dir.join("forming.csv");
        std::os::unix::fs::symlink(&mine, &result).unwrap();
        let attempts: [(&str, io::Result<()>); 4] = [
            ("create", create(&result).map(drop)),
            ("append", append(&result).map(drop)),
            ("write", write(&result, b"rows")),
            ("replace", replace(&result, b"rows")),
        ];
        for (how, outcome) in attempts {
            let e = outcome.expect_err(how);
            assert!(
                e.to_string().contains(&mine.display().to_string()),
                "{how}: {e}"
            );
        }
        assert_eq!(std::fs::read_to_string(&mine).unwrap(), "the user's data\n");
        assert!(link_at(&result).is_some(), "the link was replaced");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A link at the temporary name is refused too, and a regular temporary file left by a
    /// killed run is replaced.
    #[test]
    fn the_temporary_file_is_created_afresh() {
        let dir = folder("tmp");
        let mine = dir.join("mine.vtu");
        std::fs::write(&mine, "keep").unwrap();
        let frame = dir.join("forming_0001.vtu");
        std::os::unix::fs::symlink(&mine, tmp_path(&frame)).unwrap();
        assert!(replace(&frame, b"frame").is_err());
        assert_eq!(std::fs::read_to_string(&mine).unwrap(), "keep");
        assert!(!frame.exists());

        std::fs::remove_file(tmp_path(&frame)).unwrap();
        std::fs::write(tmp_path(&frame), "half a frame").unwrap();
        replace(&frame, b"frame").unwrap();
        assert_eq!(std::fs::read_to_string(&frame).unwrap(), "frame");
        assert!(!tmp_path(&frame).exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
