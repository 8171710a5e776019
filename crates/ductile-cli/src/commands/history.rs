//! `ductile history HISTORY`: list the steps of a history file (index, time, label) without
//! replaying it.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context as _;
use ductile_io::Base;

/// Arguments of `ductile history`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The history file (RON).
    pub history: PathBuf,
}

/// Runs the command.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let loaded = ductile_io::read_history(&args.history)
        .with_context(|| format!("cannot load history {}", args.history.display()))?;
    let base = match &loaded.base_source {
        Base::Inline(_) => "inline".to_owned(),
        Base::Reference { path, hash } => {
            format!("{path} (hash {} matches)", &hash[..hash.len().min(12)])
        }
    };
    let entries = loaded.history.entries();
    writeln!(
        out,
        "{}: {} steps, saved at step {}, base: {base}",
        args.history.display(),
        entries.len(),
        loaded.cursor
    )?;
    let width = entries.len().to_string().len();
    for (k, e) in entries.iter().enumerate() {
        let mark = if k + 1 == loaded.cursor { '*' } else { ' ' };
        writeln!(
            out,
            "{mark}{:>width$}  {}  {}",
            k + 1,
            utc(e.time_ms),
            printable(&e.label)
        )?;
    }
    Ok(0)
}

/// `text` with its control characters escaped (`\u{1b}`, `\n`, …), so that a label from a
/// file cannot move the cursor, recolour or clear the terminal it is printed to.
#[must_use]
pub fn printable(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// `time_ms` (milliseconds since the UNIX epoch) as `YYYY-MM-DD HH:MM:SS` UTC.
#[must_use]
pub fn utc(time_ms: u64) -> String {
    let secs = time_ms / 1000;
    let (days, rem) = (secs / 86_400, secs % 86_400);
    let (y, m, d) = civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02}",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

/// Proleptic Gregorian date of `days` since 1970-01-01 (H. Hinnant's `civil_from_days`).
fn civil_from_days(days: u64) -> (u64, u64, u64) {
    let z = days + 719_468;
    let era = z / 146_097;
    let doe = z % 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + u64::from(m <= 2);
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::{printable, utc};

    #[test]
    fn labels_print_without_terminal_escapes() {
        // Issue 14: history labels with control characters were printed raw.
        assert_eq!(printable("drag 'nose'"), "drag 'nose'");
        assert_eq!(printable("a\u{1b}[2Jb\nc"), "a\\u{1b}[2Jb\\nc");
    }

    #[test]
    fn dates() {
        assert_eq!(utc(0), "1970-01-01 00:00:00");
        // 2000-02-29 12:34:56 UTC = 951827696 s.
        assert_eq!(utc(951_827_696_000), "2000-02-29 12:34:56");
        assert_eq!(utc(1_763_733_600_999), "2025-11-21 14:00:00");
    }
}
