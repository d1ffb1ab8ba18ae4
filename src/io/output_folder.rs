//! One run per output folder: a run holds a lock on `FOLDER/.thermostamp.lock` while it writes
//! there, so that a second run into the same folder is refused instead of mixing its frames
//! with the first one's; the lock is the operating system's, released when the process ends,
//! however it ends (even killed), so a lock file left by a dead run is simply taken over. Once
//! the lock is taken, the files an earlier run of the same kind left there are removed, and
//! nothing else.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

/// Name of the lock file inside the output folder.
pub const LOCK_FILE: &str = ".thermostamp.lock";

/// The files a run writes into its folder, by which an earlier run's are recognised: fixed
/// names, and the frames `<series>_NNNN.vtu` of a ParaView series with its `<series>.pvd`.
/// Each name's `.tmp` (a file being written at the instant a run was killed) goes too.
#[derive(Clone, Debug, Default)]
pub struct ProductFiles {
    pub names: Vec<String>,
    pub series: Option<String>,
}

impl ProductFiles {
    /// Whether `name` (a file name in the folder) is one of these files or its `.tmp`.
    pub fn matches(&self, name: &str) -> bool {
        let name = name.strip_suffix(".tmp").unwrap_or(name);
        self.names.iter().any(|n| n == name)
            || self
                .series
                .as_deref()
                .is_some_and(|s| is_series_file(name, s))
    }
}

/// `<series>.pvd` or `<series>_` digits `.vtu`.
fn is_series_file(name: &str, series: &str) -> bool {
    let Some(rest) = name.strip_prefix(series) else {
        return false;
    };
    if rest == ".pvd" {
        return true;
    }
    rest.strip_prefix('_')
        .and_then(|r| r.strip_suffix(".vtu"))
        .is_some_and(|digits| !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
}

/// Why the folder could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    #[error(
        "{} is being written by another run ({holder}); choose another --output or wait for it",
        folder.display()
    )]
    Busy { folder: PathBuf, holder: String },
    #[error("{}: cannot {action}: {source}", path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        source: std::io::Error,
    },
}

/// The lock on an output folder, held until dropped (or the process ends): the lock file
/// held open, since closing it would release the lock.
#[derive(Debug)]
pub struct FolderLock {
    _file: File,
}

/// Creates `folder` if missing, locks it for this run (`command` is the command line the lock
/// file records, beside the process id and the start time), then removes the `products` an
/// earlier run left there. Refused, naming the holder, while another run holds the folder.
pub fn take_folder(
    folder: &Path,
    command: &str,
    products: &ProductFiles,
) -> Result<FolderLock, FolderError> {
    let io = |path: &Path, action| {
        let path = path.to_path_buf();
        move |source| FolderError::Io {
            path,
            action,
            source,
        }
    };
    std::fs::create_dir_all(folder).map_err(io(folder, "create the output folder"))?;
    let lock_path = folder.join(LOCK_FILE);
    // no truncation before the lock is ours: the holder's line names it to a refused run
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&lock_path)
        .map_err(io(&lock_path, "create the lock file"))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(TryLockError::WouldBlock) => {
            let mut holder = String::new();
            let _ = file.read_to_string(&mut holder);
            return Err(FolderError::Busy {
                folder: folder.to_path_buf(),
                holder: describe_holder(&holder),
            });
        }
        Err(TryLockError::Error(source)) => {
            return Err(FolderError::Io {
                path: lock_path,
                action: "lock the file",
                source,
            })
        }
    }
    let line = format!(
        "pid {}, `{}`, started at {}\n",
        std::process::id(),
        command,
        utc_now()
    );
    file.set_len(0)
        .and_then(|()| file.rewind())
        .and_then(|()| file.write_all(line.as_bytes()))
        .map_err(io(&lock_path, "write the lock file"))?;
    clear_products(folder, products)?;
    Ok(FolderLock { _file: file })
}

/// The holder as its lock file names it; a holder that has not written its line yet is still
/// a holder.
fn describe_holder(text: &str) -> String {
    match text.lines().next().map(str::trim) {
        Some(line) if !line.is_empty() => line.to_string(),
        _ => "a run that has just started".into(),
    }
}

/// Removes the regular files of `products` in `folder`. A symbolic link of such a name is
/// the user's doing (it points where the results should go), so it stays.
fn clear_products(folder: &Path, products: &ProductFiles) -> Result<(), FolderError> {
    let entries = std::fs::read_dir(folder).map_err(|source| FolderError::Io {
        path: folder.to_path_buf(),
        action: "list the output folder",
        source,
    })?;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        let regular = entry.file_type().is_ok_and(|t| t.is_file());
        if regular && products.matches(name) {
            let path = entry.path();
            std::fs::remove_file(&path).map_err(|source| FolderError::Io {
                path,
                action: "remove the earlier run's file",
                source,
            })?;
        }
    }
    Ok(())
}

/// The current time as `YYYY-MM-DD HH:MM:SS UTC`.
fn utc_now() -> String {
    let seconds = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rest) = (seconds / 86_400, seconds % 86_400);
    let (y, m, d) = civil_from_days(days as i64);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC",
        rest / 3600,
        rest % 3600 / 60,
        rest % 60
    )
}

/// Year, month, day of the day `days` after 1970-01-01 (proleptic Gregorian calendar; H.
/// Hinnant's algorithm).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_folder(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("thermostamp-folder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn forming_products() -> ProductFiles {
        ProductFiles {
            names: vec!["forming.csv".into(), "formed-blank.inp".into()],
            series: Some("forming".into()),
        }
    }

    #[test]
    fn recognises_the_products_and_nothing_else() {
        let p = forming_products();
        for name in [
            "forming.csv",
            "forming.csv.tmp",
            "forming.pvd",
            "forming_0000.vtu",
            "forming_12345.vtu.tmp",
            "formed-blank.inp",
        ] {
            assert!(p.matches(name), "{name}");
        }
        for name in [
            "forming.toml",
            "forming_.vtu",
            "forming_00a1.vtu",
            "forming_0001.vtu.bak",
            "my-forming.csv",
            "notes.txt",
            LOCK_FILE,
        ] {
            assert!(!p.matches(name), "{name}");
        }
    }

    #[test]
    fn a_second_lock_is_refused_naming_the_first_and_clearing_spares_other_files() {
        let dir = temp_folder("lock");
        std::fs::create_dir_all(&dir).unwrap();
        for name in ["forming_0007.vtu", "forming.csv", "notes.txt"] {
            std::fs::write(dir.join(name), "old").unwrap();
        }
        let first = take_folder(&dir, "thermostamp run a.toml", &forming_products()).unwrap();
        assert!(!dir.join("forming_0007.vtu").exists());
        assert!(!dir.join("forming.csv").exists());
        assert!(dir.join("notes.txt").exists());
        let e = take_folder(&dir, "thermostamp run b.toml", &forming_products()).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains(&format!("pid {}", std::process::id()))
                && text.contains("`thermostamp run a.toml`")
                && text.contains("is being written by another run"),
            "{text}"
        );
        drop(first);
        take_folder(&dir, "thermostamp run b.toml", &forming_products()).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn dates_are_the_calendar_ones() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(20_454), (2026, 1, 1));
    }
}
