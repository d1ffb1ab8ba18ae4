//! Taking a study's folder (docs/study.md, "One study per folder"): its lock, the record of
//! which study it holds, and no symbolic link where the study writes. A sweep, or the summary
//! alone, takes the folder whole: a second one is refused, naming the first. The cases of a
//! study run one per process (`--case N`) share it, each holding its own case's lock, and
//! exclude a sweep meanwhile.

use super::file::Study;
use super::identity::{self, case_folders};
use super::summary;
use crate::io::output_folder::{clear_products, lock_folder, FolderLock, Hold, LOCK_FILE};
use crate::io::product_file;

/// Takes the study's folder whole for a sweep or a summary (`command` is the command line the
/// lock records), records the study there, refuses a case folder that is a symbolic link, and
/// removes the summary an earlier sweep wrote (refusing a link in its place).
pub fn take_whole(study: &Study, command: &str) -> anyhow::Result<FolderLock> {
    let lock = lock_folder(&study.folder, LOCK_FILE, Hold::Whole, command)?;
    identity::claim(study)?;
    let linked = case_folders(&study.folder)
        .find_map(|path| product_file::link_at(&path).map(|link| (path, link)));
    if let Some((path, link)) = linked {
        anyhow::bail!("{}: {link}", path.display());
    }
    clear_products(&study.folder, &summary::products())?;
    Ok(lock)
}

/// Takes the study's folder beside the other processes running its cases, and records the
/// study there.
pub fn take_shared(study: &Study, command: &str) -> anyhow::Result<FolderLock> {
    let lock = lock_folder(&study.folder, LOCK_FILE, Hold::Shared, command)?;
    identity::claim(study)?;
    Ok(lock)
}
