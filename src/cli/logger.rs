//! The binary's `log` backend: the library's warnings printed on stderr as `warning: ...`
//! (errors as `error: ...`), the Vulkan validation layer's lines as they are.

use std::io::Write;

use log::{Level, LevelFilter, Log, Metadata, Record};

struct Stderr;

impl Log for Stderr {
    fn enabled(&self, metadata: &Metadata) -> bool {
        metadata.level() <= Level::Warn
    }

    fn log(&self, record: &Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        // Writes never panic: a closed stderr (or a validation message from a driver thread)
        // loses the line, nothing else.
        let mut err = std::io::stderr().lock();
        let _ = match (record.target(), record.level()) {
            ("vulkan", _) => writeln!(err, "{}", record.args()),
            (_, Level::Error) => writeln!(err, "error: {}", record.args()),
            _ => writeln!(err, "warning: {}", record.args()),
        };
    }

    fn flush(&self) {}
}

/// Installs the logger (once; a second call changes nothing).
pub fn install() {
    if log::set_logger(&Stderr).is_ok() {
        log::set_max_level(LevelFilter::Warn);
    }
}
