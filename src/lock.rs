//! Advisory locks on output folders, so two irad processes never write one folder's files at
//! once: `FolderLock` (a render's files renamed into place as one set, writers one at a time)
//! and `HolderLock` (a suite or merge output folder, held for the whole run, with a lock file
//! naming its holder).
//!
//! Both use `flock(2)`: the kernel releases the lock when its holder exits, however it exits,
//! so a lock left by a dead process never blocks anyone (a pid file alone cannot tell a dead
//! holder from a live one whose pid was reused). The lock file's text, the holder's pid and
//! host, only makes the messages useful. On systems without `flock` the locks are no-ops.

use std::fs::{self, File, OpenOptions};
use std::io::{Read as _, Write as _};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};

/// An exclusive lock on a folder itself (its directory handle), released on drop.
pub struct FolderLock {
    _dir: File,
}

impl FolderLock {
    /// Waits until no other process holds `dir`'s lock, then holds it.
    pub fn wait(dir: &Path) -> Result<FolderLock> {
        let file =
            File::open(dir).with_context(|| format!("opening the folder {}", dir.display()))?;
        flock(&file, false).with_context(|| format!("locking the folder {}", dir.display()))?;
        Ok(FolderLock { _dir: file })
    }
}

/// The lock file of an output folder that one process writes at a time (a suite's or a
/// merge's), held until drop, which removes it.
pub struct HolderLock {
    file: File,
    path: PathBuf,
}

/// What `HolderLock::acquire` found.
pub struct Acquired {
    pub lock: HolderLock,
    /// The holder named by a lock file whose process is gone (a crash, a kill, a second
    /// Ctrl-C): its lock was taken over.
    pub stale: Option<String>,
}

impl HolderLock {
    /// The lock file `LOCK_FILE` in `dir` (which must exist): held by this process, or an
    /// error naming `dir` and the live holder.
    pub fn acquire(dir: &Path) -> Result<Acquired> {
        HolderLock::acquire_or(
            dir,
            "wait for it to finish, or choose another output folder",
        )
    }

    /// As `acquire`, with `advice` ending the error when another process holds `dir`.
    pub fn acquire_or(dir: &Path, advice: &str) -> Result<Acquired> {
        let path = dir.join(LOCK_FILE);
        // The file can be removed by its holder between our open and our lock (it removes it
        // when it is done): then we locked a file no one else will see, so open it again.
        for _ in 0..100 {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .with_context(|| format!("opening the lock file {}", path.display()))?;
            let mut text = String::new();
            match flock(&file, true) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    let _ = file.read_to_string(&mut text);
                    bail!(
                        "{} is being written by {} (lock file {}): {advice}",
                        dir.display(),
                        holder_words(&text),
                        path.display()
                    );
                }
                Err(e) => {
                    return Err(e).with_context(|| format!("locking {}", path.display()));
                }
            }
            if !same_file(&file, &path) {
                continue;
            }
            file.read_to_string(&mut text)
                .with_context(|| format!("reading the lock file {}", path.display()))?;
            let stale = (!text.trim().is_empty()).then(|| holder_words(&text));
            file.set_len(0)
                .and_then(|_| {
                    use std::io::Seek as _;
                    file.seek(std::io::SeekFrom::Start(0))?;
                    file.write_all(holder_text().as_bytes())?;
                    file.flush()
                })
                .with_context(|| format!("writing the lock file {}", path.display()))?;
            return Ok(Acquired {
                lock: HolderLock { file, path },
                stale,
            });
        }
        bail!(
            "could not lock {}: its lock file kept being replaced",
            path.display()
        )
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for HolderLock {
    fn drop(&mut self) {
        // Remove the file only while it is still ours (a merge moves the folder it was in),
        // and before the lock goes, so a waiting process finds either our locked file or none.
        if same_file(&self.file, &self.path) {
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// The lock file's name inside a locked folder.
pub const LOCK_FILE: &str = ".irad-lock";

/// What a lock file says of its holder: "pid 1234 on host".
fn holder_text() -> String {
    format!("pid {} on {}\n", std::process::id(), host())
}

/// A holder for messages, from its lock file's text.
fn holder_words(text: &str) -> String {
    match text.trim() {
        "" => "another irad process".to_string(),
        t => format!("irad ({t})"),
    }
}

fn host() -> String {
    fs::read_to_string("/proc/sys/kernel/hostname")
        .or_else(|_| fs::read_to_string("/etc/hostname"))
        .map(|h| h.trim().to_string())
        .ok()
        .filter(|h| !h.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "this host".into())
}

#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt as _;
    match (file.metadata(), fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_file: &File, path: &Path) -> bool {
    path.exists()
}

/// `flock(LOCK_EX)`, failing with `WouldBlock` at once when `try_only` and held elsewhere.
#[cfg(unix)]
fn flock(file: &File, try_only: bool) -> std::io::Result<()> {
    use std::os::unix::io::AsRawFd as _;
    let op = libc::LOCK_EX | if try_only { libc::LOCK_NB } else { 0 };
    loop {
        // SAFETY: flock on a file descriptor this `File` owns for the call's duration.
        if unsafe { libc::flock(file.as_raw_fd(), op) } == 0 {
            return Ok(());
        }
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(e);
        }
    }
}

#[cfg(not(unix))]
fn flock(_file: &File, _try_only: bool) -> std::io::Result<()> {
    Ok(())
}
