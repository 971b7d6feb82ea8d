//! The binary's `log` backend: irad's warnings printed on stderr as `warning: ...` (errors
//! as `error: ...`, notes of a long step under way, `log::info!`, as `note: ...`), the Vulkan validation layer's lines as they are; other crates' records
//! (naga's notes on SPIR-V decorations it skips, obvhs) are left out, as before the facade. A
//! progress bar on screen is cleared for the line and drawn again after it.

use std::io::Write;
use std::sync::Mutex;

use indicatif::{MultiProgress, ProgressBar};
use log::{Level, LevelFilter, Log, Metadata, Record};

/// The bars on screen, which a printed line must not cut through.
pub enum Bars {
    One(ProgressBar),
    Several(MultiProgress),
}

static ON_SCREEN: Mutex<Option<Bars>> = Mutex::new(None);

/// Sets the bars lines are printed around (None: none on screen).
pub fn on_screen(bars: Option<Bars>) {
    *ON_SCREEN.lock().unwrap_or_else(|e| e.into_inner()) = bars;
}

struct Stderr;

impl Log for Stderr {
    fn enabled(&self, metadata: &Metadata) -> bool {
        let target = metadata.target();
        match target {
            "vulkan" => metadata.level() <= Level::Warn,
            t => t.starts_with("irad") && metadata.level() <= Level::Info,
        }
    }

    fn log(&self, record: &Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        let line = match (record.target(), record.level()) {
            ("vulkan", _) => format!("{}", record.args()),
            (_, Level::Error) => format!("error: {}", record.args()),
            (_, Level::Info) => format!("note: {}", record.args()),
            _ => format!("warning: {}", record.args()),
        };
        // Writes never panic: a closed stderr (or a validation message from a driver thread)
        // loses the line, nothing else.
        let print = || {
            let _ = writeln!(std::io::stderr().lock(), "{line}");
        };
        match &*ON_SCREEN.lock().unwrap_or_else(|e| e.into_inner()) {
            Some(Bars::One(bar)) if !bar.is_finished() => bar.suspend(print),
            Some(Bars::Several(bars)) => bars.suspend(print),
            _ => print(),
        }
    }

    fn flush(&self) {}
}

/// Installs the logger (once; a second call changes nothing).
pub fn install() {
    if log::set_logger(&Stderr).is_ok() {
        log::set_max_level(LevelFilter::Info);
    }
}
