//! Memory checks shared by every job that allocates in proportion to its input (the PE
//! march, the radio-map builder, the planner): refuse before allocating, with the bytes.

use crate::error::{CoreError, Result};

/// Memory this machine reports as available (Linux `MemAvailable`), bytes.
pub fn available_memory_bytes() -> Option<usize> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: usize = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Refuses a job needing `bytes` if it exceeds 80% of the available memory.
pub fn check_memory(bytes: usize) -> Result<()> {
    check_memory_for("grid", "use fewer samples, steps or recorded rows", bytes)
}

/// Refuses a job needing `bytes` if it exceeds 80% of the available memory; the error names
/// the argument `what` that sets the size and says how to shrink it (`hint`).
pub fn check_memory_for(what: &'static str, hint: &str, bytes: usize) -> Result<()> {
    if let Some(avail) = available_memory_bytes()
        && bytes as f64 > 0.8 * avail as f64
    {
        return Err(CoreError::invalid(
            what,
            format!(
                "needs {:.2} GB but this machine has {:.2} GB available (at most 80% may be \
                 used); {hint}",
                bytes as f64 / 1e9,
                avail as f64 / 1e9
            ),
            bytes,
        ));
    }
    Ok(())
}
