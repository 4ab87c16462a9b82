//! The memory this process may still take, asked of the system: loaders
//! refuse a file by what it would take, by name, before an allocation
//! fails for it.

/// Bytes of memory this process may still take, where the system says
/// (Linux): the least of what the system can give (its estimate of memory
/// available without swapping, and the free swap), what the process's
/// control group has left under its limit (a container's; cgroup v2 or
/// v1; its reclaimable page cache counted as left), and what its
/// address-space limit (`ulimit -v`) leaves beside the address space it
/// already holds.
pub fn available() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let system = (field(&meminfo, "MemAvailable:", "kB")? + field(&meminfo, "SwapFree:", "kB").unwrap_or(0)) * 1024;
    let read = |path: &str| std::fs::read_to_string(path).ok()?.trim().parse::<u64>().ok();
    // The group's usage counts the page cache it holds, which the kernel
    // takes back before it refuses memory: its inactive files (the model
    // just read among them) are left out, as container runtimes count it.
    let left = |folder: &str, limit: &str, usage: &str, inactive: &str| {
        let stat = std::fs::read_to_string(format!("{folder}/memory.stat")).unwrap_or_default();
        let reclaimable = field(&stat, inactive, "").unwrap_or(0);
        let used = read(&format!("{folder}/{usage}"))?.saturating_sub(reclaimable);
        Some(read(&format!("{folder}/{limit}"))?.saturating_sub(used))
    };
    let group = left("/sys/fs/cgroup", "memory.max", "memory.current", "inactive_file ").or_else(|| {
        left(
            "/sys/fs/cgroup/memory",
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
            "total_inactive_file ",
        )
    });
    let address_space = || {
        let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
        // "Max address space  <soft>  <hard>  bytes": the soft limit binds.
        let soft = field(&limits, "Max address space", "")?;
        let held = field(&std::fs::read_to_string("/proc/self/status").ok()?, "VmSize:", "kB")? * 1024;
        Some(soft.saturating_sub(held))
    };
    [Some(system), group, address_space()].into_iter().flatten().min()
}

/// The number after `name` on the line of `text` that starts with it, in
/// `unit` (its first word after `name`, whatever follows); none where the
/// line is missing or the word is no number ("unlimited").
fn field(text: &str, name: &str, unit: &str) -> Option<u64> {
    let line = text.lines().find_map(|line| line.strip_prefix(name))?;
    let number = line.split_whitespace().next()?;
    let rest = line.trim_start().strip_prefix(number)?.trim_start();
    match unit.is_empty() || rest.starts_with(unit) {
        true => number.parse().ok(),
        false => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_is_its_first_word_in_its_unit_and_unlimited_is_no_number() {
        let meminfo = "MemTotal:       24000000 kB\nMemAvailable:   20000000 kB\n";
        assert_eq!(field(meminfo, "MemAvailable:", "kB"), Some(20_000_000));
        assert_eq!(field(meminfo, "SwapFree:", "kB"), None);
        let limits = "Max address space         614400000            614400000            bytes\n";
        assert_eq!(field(limits, "Max address space", ""), Some(614_400_000));
        let unlimited = "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(field(unlimited, "Max address space", ""), None);
        assert_eq!(field("VmSize:\t    3892 MB\n", "VmSize:", "kB"), None);
        let stat = "inactive_anon 4096\ninactive_file 81920\n";
        assert_eq!(field(stat, "inactive_file ", ""), Some(81920));
        assert_eq!(field(stat, "total_inactive_file ", ""), None);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn linux_says_how_much_memory_is_left() {
        assert!(available().is_some_and(|bytes| bytes > 0));
    }
}
