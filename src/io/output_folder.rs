//! One run per output folder: a run holds a lock on `FOLDER/.thermostamp.lock` while it writes
//! there, so that a second run into the same folder is refused instead of mixing its frames
//! with the first one's; the lock is the operating system's, released when the process ends,
//! however it ends (even killed), so a lock file left by a dead run is simply taken over. Once
//! the lock is taken, the files an earlier run of the same kind left there are removed, and
//! nothing else. A symbolic link under one of those names is the user's (it points at their
//! own file), and is never written through nor removed: the run is refused, naming it. A lock
//! may also be shared, by processes that each write their own part of the folder (the cases
//! of a study run one per process): they exclude a run that takes the folder whole.

use super::product_file::{self, LinkInTheWay};
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

/// `<series>.pvd`, `<series>_` digits `.vtu` or a further part of a frame, `<series>_` digits
/// `_<part>.vtu` (`io::vtk::PvdSeries`).
fn is_series_file(name: &str, series: &str) -> bool {
    let Some(rest) = name.strip_prefix(series) else {
        return false;
    };
    if rest == ".pvd" {
        return true;
    }
    let Some(frame) = rest.strip_prefix('_').and_then(|r| r.strip_suffix(".vtu")) else {
        return false;
    };
    let (digits, part) = match frame.split_once('_') {
        Some((digits, part)) => (digits, Some(part)),
        None => (frame, None),
    };
    let word = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'-');
    !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) && part.is_none_or(word)
}

/// Who holds a folder that could not be taken.
#[derive(Debug)]
pub enum Holder {
    /// A run that holds it whole: its lock file's line (pid, command line, start time).
    Run(String),
    /// Processes that share it.
    Sharing,
}

impl std::fmt::Display for Holder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Holder::Run(line) => write!(f, "another run ({line})"),
            Holder::Sharing => write!(
                f,
                "processes that share it (the cases of a study run with `thermostamp sweep \
                 --case`)"
            ),
        }
    }
}

/// Why the folder could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    #[error(
        "{} is being written by {holder}; choose another --output or wait for it",
        folder.display()
    )]
    Busy { folder: PathBuf, holder: Holder },
    #[error("{}: {link}", path.display())]
    Link { path: PathBuf, link: LinkInTheWay },
    #[error(
        "the output folder {} is a symbolic link to {}, {problem}",
        path.display(),
        target.display()
    )]
    BrokenLink {
        path: PathBuf,
        target: PathBuf,
        problem: &'static str,
    },
    #[error("the output folder {} is a loop of symbolic links", path.display())]
    LinkLoop { path: PathBuf },
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

/// How a folder is held.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hold {
    /// By this process alone.
    Whole,
    /// Beside other processes sharing it, none holding it whole.
    Shared,
}

/// Creates `folder` if missing, locks it for this run (`command` is the command line the lock
/// file records, beside the process id and the start time), then removes the `products` an
/// earlier run left there. Refused, naming the holder, while another run holds the folder;
/// refused, naming it, where one of the `products` is a symbolic link.
pub fn take_folder(
    folder: &Path,
    command: &str,
    products: &ProductFiles,
) -> Result<FolderLock, FolderError> {
    let lock = lock_folder(folder, LOCK_FILE, Hold::Whole, command)?;
    clear_products(folder, products)?;
    Ok(lock)
}

/// Creates `folder` if missing and locks it through its lock file `lock_name`, whole or
/// shared. A process holding it whole records its line (pid, `command`, start time) in the
/// lock file, by which a refused one names it.
pub fn lock_folder(
    folder: &Path,
    lock_name: &str,
    hold: Hold,
    command: &str,
) -> Result<FolderLock, FolderError> {
    create_folder(folder)?;
    let lock_path = folder.join(lock_name);
    // no truncation before the lock is ours: the holder's line names it to a refused run
    let mut file = product_file::open(
        &lock_path,
        OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false),
    )
    .map_err(|source| link_or_io(&lock_path, "create the lock file", source))?;
    let locked = match hold {
        Hold::Whole => file.try_lock(),
        Hold::Shared => file.try_lock_shared(),
    };
    match locked {
        Ok(()) => {}
        Err(TryLockError::WouldBlock) => {
            return Err(FolderError::Busy {
                folder: folder.to_path_buf(),
                holder: holder(&mut file),
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
    if hold == Hold::Whole {
        let line = format!(
            "pid {}, `{}`, started at {}\n",
            std::process::id(),
            command,
            utc_now()
        );
        file.set_len(0)
            .and_then(|()| file.rewind())
            .and_then(|()| file.write_all(line.as_bytes()))
            .map_err(|source| FolderError::Io {
                path: lock_path,
                action: "write the lock file",
                source,
            })?;
    }
    Ok(FolderLock { _file: file })
}

/// Who holds the lock that `file` could not take: processes sharing it when a shared lock
/// can be had beside them (they write no line), else the run whose line the file holds.
fn holder(file: &mut File) -> Holder {
    if file.try_lock_shared().is_ok() {
        let _ = file.unlock();
        return Holder::Sharing;
    }
    let mut text = String::new();
    let _ = file.read_to_string(&mut text);
    Holder::Run(describe_holder(&text))
}

/// The holder as its lock file names it; a holder that has not written its line yet is still
/// a holder.
fn describe_holder(text: &str) -> String {
    match text.lines().next().map(str::trim) {
        Some(line) if !line.is_empty() => line.to_string(),
        _ => "a run that has just started".into(),
    }
}

/// Creates `folder` and its parents. A symbolic link on the way that leads nowhere (to
/// nothing, to a file, or round in a loop) is named, since the operating system's own word
/// for it ("File exists") says nothing of the link.
pub fn create_folder(folder: &Path) -> Result<(), FolderError> {
    std::fs::create_dir_all(folder).map_err(|source| {
        broken_link(folder).unwrap_or(FolderError::Io {
            path: folder.to_path_buf(),
            action: "create the output folder",
            source,
        })
    })
}

/// The first of `path`'s ancestors (itself included), from the root down, that is a symbolic
/// link to no folder.
fn broken_link(path: &Path) -> Option<FolderError> {
    let mut ancestors: Vec<&Path> = path
        .ancestors()
        .filter(|p| !p.as_os_str().is_empty())
        .collect();
    ancestors.reverse();
    ancestors.into_iter().find_map(|p| {
        let target = std::fs::read_link(p).ok()?;
        let broken = |problem| {
            Some(FolderError::BrokenLink {
                path: p.to_path_buf(),
                target: target.clone(),
                problem,
            })
        };
        match std::fs::metadata(p) {
            Ok(meta) if meta.is_dir() => None,
            Ok(_) => broken("which is not a folder"),
            Err(e) if e.raw_os_error() == Some(libc::ELOOP) => Some(FolderError::LinkLoop {
                path: p.to_path_buf(),
            }),
            Err(_) => broken("which does not exist"),
        }
    })
}

/// [`FolderError::Link`] for a link in the way, else [`FolderError::Io`].
fn link_or_io(path: &Path, action: &'static str, source: std::io::Error) -> FolderError {
    match product_file::link_at(path) {
        Some(link) => FolderError::Link {
            path: path.to_path_buf(),
            link,
        },
        None => FolderError::Io {
            path: path.to_path_buf(),
            action,
            source,
        },
    }
}

/// Removes the regular files of `products` in `folder`. A symbolic link of such a name is
/// the user's doing (it points at their own file), so nothing is removed and the run is
/// refused, naming it: writing the results would write through it.
pub fn clear_products(folder: &Path, products: &ProductFiles) -> Result<(), FolderError> {
    let entries: Vec<std::fs::DirEntry> = std::fs::read_dir(folder)
        .map_err(|source| FolderError::Io {
            path: folder.to_path_buf(),
            action: "list the output folder",
            source,
        })?
        .flatten()
        .filter(|entry| {
            entry
                .file_name()
                .to_str()
                .is_some_and(|n| products.matches(n))
        })
        .collect();
    if let Some(link) = entries
        .iter()
        .find_map(|entry| product_file::link_at(&entry.path()).map(|link| (entry.path(), link)))
    {
        return Err(FolderError::Link {
            path: link.0,
            link: link.1,
        });
    }
    for entry in entries {
        if entry.file_type().is_ok_and(|t| t.is_file()) {
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
            "forming_0003_tools.vtu",
            "formed-blank.inp",
        ] {
            assert!(p.matches(name), "{name}");
        }
        for name in [
            "forming.toml",
            "forming_.vtu",
            "forming_00a1.vtu",
            "forming_0001.vtu.bak",
            "forming_0001_.vtu",
            "forming_0001_my notes.vtu",
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

    /// A link under a product's name (here the `.tmp` of a frame) refuses the folder, naming
    /// the link and its target, and nothing is removed: neither the link nor an earlier run's
    /// regular files.
    #[test]
    fn a_link_among_the_products_refuses_the_folder_and_removes_nothing() {
        let dir = temp_folder("link");
        std::fs::create_dir_all(&dir).unwrap();
        let mine = dir.join("mine.vtu");
        std::fs::write(&mine, "the user's").unwrap();
        std::os::unix::fs::symlink(&mine, dir.join("forming_0002.vtu.tmp")).unwrap();
        std::fs::write(dir.join("forming.csv"), "old").unwrap();
        let e = take_folder(&dir, "run", &forming_products()).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("forming_0002.vtu.tmp") && text.contains(&mine.display().to_string()),
            "{text}"
        );
        assert!(dir.join("forming.csv").exists());
        assert!(dir.join("forming_0002.vtu.tmp").is_symlink());
        assert_eq!(std::fs::read_to_string(&mine).unwrap(), "the user's");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Shared holds coexist; a whole hold is refused beside them, naming them as sharers, and
    /// a shared one beside a whole one names the run.
    #[test]
    fn shared_holds_coexist_and_exclude_a_whole_one() {
        let dir = temp_folder("shared");
        let a = lock_folder(&dir, LOCK_FILE, Hold::Shared, "case 1").unwrap();
        let b = lock_folder(&dir, LOCK_FILE, Hold::Shared, "case 2").unwrap();
        let e = lock_folder(&dir, LOCK_FILE, Hold::Whole, "sweep").unwrap_err();
        assert!(
            matches!(
                e,
                FolderError::Busy {
                    holder: Holder::Sharing,
                    ..
                }
            ),
            "{e}"
        );
        drop((a, b));
        let whole = lock_folder(&dir, LOCK_FILE, Hold::Whole, "sweep s.toml").unwrap();
        let e = lock_folder(&dir, LOCK_FILE, Hold::Shared, "case 1").unwrap_err();
        assert!(e.to_string().contains("`sweep s.toml`"), "{e}");
        drop(whole);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// An output folder through a link to nothing, to a file, or round a loop is named as
    /// such; through a link to a folder it is that folder.
    #[test]
    fn broken_links_to_the_folder_are_named() {
        let dir = temp_folder("broken");
        std::fs::create_dir_all(dir.join("real")).unwrap();
        std::fs::write(dir.join("file"), "").unwrap();
        let link = |name: &str, to: &str| {
            std::os::unix::fs::symlink(dir.join(to), dir.join(name)).unwrap();
            dir.join(name)
        };
        let expect = |folder: PathBuf, piece: &str| {
            let e = create_folder(&folder).unwrap_err().to_string();
            assert!(e.contains(piece), "{e}");
        };
        expect(link("dangling", "nowhere"), "which does not exist");
        expect(link("to-file", "file").join("sub"), "which is not a folder");
        link("loop-a", "loop-b");
        expect(link("loop-b", "loop-a"), "a loop of symbolic links");
        create_folder(&link("to-real", "real").join("sub")).unwrap();
        assert!(dir.join("real/sub").is_dir());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn dates_are_the_calendar_ones() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(20_454), (2026, 1, 1));
    }
}
