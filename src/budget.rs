//! The memory budget: how much memory one run may plan to use, checked
//! against an estimate before anything large is allocated, so that an
//! oversized scene, output or image is refused with a message naming it
//! instead of aborting the process when an allocation fails.
//!
//! The budget is `AERIAL_MEMORY_BUDGET` when set (bytes, or a number with
//! a `K`, `M`, `G` or `T` suffix, powers of 1024), otherwise half of the
//! smallest of: the machine's physical memory, the cgroup memory limit and
//! the address-space limit (`ulimit -v`). Half, because the estimates cover
//! the large buffers only, and the driver, shader compiler and allocator
//! need room of their own. On a CPU driver such as lavapipe, "GPU" memory is
//! this same system memory, so it counts against the same budget.

use std::fmt;

/// The environment variable that sets the budget.
pub const ENV: &str = "AERIAL_MEMORY_BUDGET";

/// Used when the machine's memory cannot be read.
const FALLBACK_BYTES: u64 = 4 << 30;

/// A memory budget and where it came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    pub bytes: u64,
    /// True when set by [`ENV`], false for the machine default.
    pub from_env: bool,
}

/// A planned use of memory that the budget does not allow, or a bad setting.
#[derive(Debug, thiserror::Error)]
pub enum BudgetError {
    #[error(
        "{what} needs about {} of memory, more than the memory budget of {} ({}); \
         make it smaller, or set {ENV} (e.g. {ENV}=16G) if the machine has the memory",
        Bytes(*need), Bytes(budget.bytes), budget.origin()
    )]
    TooLarge {
        what: String,
        need: u64,
        budget: MemoryBudget,
    },
    #[error("{ENV}={value:?}: {reason}")]
    BadSetting { value: String, reason: String },
}

impl MemoryBudget {
    /// The budget from [`ENV`], or the machine default.
    pub fn from_env() -> Result<MemoryBudget, BudgetError> {
        match std::env::var(ENV) {
            Ok(value) => Ok(MemoryBudget {
                bytes: parse_size(&value).map_err(|reason| BudgetError::BadSetting {
                    value: value.clone(),
                    reason,
                })?,
                from_env: true,
            }),
            Err(_) => Ok(MemoryBudget {
                bytes: machine_default(),
                from_env: false,
            }),
        }
    }

    /// Fails when `need` bytes for `what` exceed the budget.
    pub fn check(&self, what: impl Into<String>, need: u64) -> Result<(), BudgetError> {
        if need > self.bytes {
            return Err(BudgetError::TooLarge {
                what: what.into(),
                need,
                budget: *self,
            });
        }
        Ok(())
    }

    fn origin(&self) -> String {
        if self.from_env {
            format!("set by {ENV}")
        } else {
            "half of this machine's memory limit".to_string()
        }
    }
}

/// Parses `123`, `512K`, `64M`, `2G`, `1T` (also `2GB`, `2GiB`, any case).
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let digits = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(digits);
    let number: f64 = number
        .parse()
        .map_err(|_| "expected a size such as 512M or 4G".to_string())?;
    let shift = match unit.trim().to_ascii_uppercase().as_str() {
        "" | "B" => 0,
        "K" | "KB" | "KIB" => 10,
        "M" | "MB" | "MIB" => 20,
        "G" | "GB" | "GIB" => 30,
        "T" | "TB" | "TIB" => 40,
        other => return Err(format!("unknown unit {other:?} (use K, M, G or T)")),
    };
    let bytes = number * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes < u64::MAX as f64) {
        return Err(format!("too large: at most {}", Bytes(u64::MAX)));
    }
    if bytes < 1.0 {
        return Err("must be at least 1 byte".to_string());
    }
    Ok(bytes as u64)
}

/// Half the smallest memory limit this process is under.
fn machine_default() -> u64 {
    let mut limit = physical_memory().unwrap_or(FALLBACK_BYTES * 2);
    if let Some(cgroup) = cgroup_limit() {
        limit = limit.min(cgroup);
    }
    if let Some(address_space) = address_space_limit() {
        limit = limit.min(address_space);
    }
    limit / 2
}

fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn cgroup_limit() -> Option<u64> {
    // cgroup v2, then v1; "max" or an absurdly large v1 value means none.
    for path in [
        "/sys/fs/cgroup/memory.max",
        "/sys/fs/cgroup/memory/memory.limit_in_bytes",
    ] {
        if let Ok(text) = std::fs::read_to_string(path) {
            if let Ok(v) = text.trim().parse::<u64>() {
                if v < (1 << 60) {
                    return Some(v);
                }
            }
        }
    }
    None
}

#[cfg(unix)]
// rlim_t is u64 on Linux but not on every Unix.
#[allow(clippy::unnecessary_cast)]
fn address_space_limit() -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes into the struct we own and reads nothing else.
    let ok = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } == 0;
    (ok && limit.rlim_cur != libc::RLIM_INFINITY).then_some(limit.rlim_cur as u64)
}

#[cfg(not(unix))]
fn address_space_limit() -> Option<u64> {
    None
}

/// A byte count printed in binary units (`1.5 GiB`).
#[derive(Clone, Copy, Debug)]
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let units = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
        let mut value = self.0 as f64;
        let mut unit = 0;
        while value >= 1024.0 && unit + 1 < units.len() {
            value /= 1024.0;
            unit += 1;
        }
        if unit == 0 {
            write!(f, "{} bytes", self.0)
        } else {
            write!(f, "{value:.1} {}", units[unit])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_sizes_parse_and_bad_ones_are_refused() {
        assert_eq!(parse_size("4096").unwrap(), 4096);
        assert_eq!(parse_size("64M").unwrap(), 64 << 20);
        assert_eq!(parse_size("2gib").unwrap(), 2 << 30);
        assert_eq!(parse_size("1.5G").unwrap(), 3 << 29);
        for bad in ["", "x", "0", "-1G", "5Q", "1e400"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
        assert!(machine_default() > 0);
        let budget = MemoryBudget {
            bytes: 1 << 20,
            from_env: true,
        };
        let msg = budget.check("output 4x4", 2 << 20).unwrap_err().to_string();
        assert!(
            msg.contains("output 4x4") && msg.contains("2.0 MiB") && msg.contains(ENV),
            "{msg}"
        );
        assert!(budget.check("small", 1 << 20).is_ok());
    }
}
