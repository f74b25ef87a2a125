//! Where and when a benchmark ran, recorded in its JSON (`"provenance"`) so that the generated
//! page can say it without guessing: the UTC date of the run, the commit of the source tree
//! (with `-dirty` when tracked files differ from it) and the machine (processor model, logical
//! CPUs, memory, operating system). A figure that cannot be read (no `git`, no `/proc`) is
//! `null`, never invented.

use serde_json::{Value, json};
use std::path::Path;
use std::process::Command;

/// The provenance of a run started now in the repository at `root`:
/// `{"date", "commit", "machine": {"cpu", "logical_cpus", "memory_gib", "os"}}`.
pub fn provenance(root: &Path) -> Value {
    json!({
        "date": humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string(),
        "commit": commit(root),
        "machine": machine(),
    })
}

/// `git rev-parse HEAD` of `root`, suffixed `-dirty` when `git status` lists a changed tracked
/// file; `None` if git cannot tell.
fn commit(root: &Path) -> Option<String> {
    let git = |args: &[&str]| {
        let out = Command::new("git")
            .args(args)
            .current_dir(root)
            .output()
            .ok()?;
        out.status
            .success()
            .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
    };
    let head = git(&["rev-parse", "HEAD"])?;
    let changed = git(&["status", "--porcelain", "--untracked-files=no"])?;
    Some(if changed.is_empty() {
        head
    } else {
        format!("{head}-dirty")
    })
}

/// The machine: processor model (`/proc/cpuinfo`), logical CPUs this process may use, total
/// memory in GiB (`/proc/meminfo`), operating system and architecture.
fn machine() -> Value {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let cpu = cpuinfo
        .lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split_once(':'))
        .map(|(_, v)| v.trim().to_string());
    let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    let memory_gib = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map(|kib| kib / (1024.0 * 1024.0));
    json!({
        "cpu": cpu,
        "logical_cpus": std::thread::available_parallelism().map_or(1, |n| n.get()),
        "memory_gib": memory_gib,
        "os": format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
    })
}

#[cfg(test)]
mod tests {
    use super::provenance;

    #[test]
    fn the_provenance_names_a_date_a_machine_and_a_commit() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let p = provenance(&root);
        let date = p["date"].as_str().expect("a date");
        // RFC 3339 in UTC to the second, e.g. 2000-01-01T00:00:00Z.
        assert_eq!(date.len(), 20, "{date}");
        assert!(date.ends_with('Z') && &date[4..5] == "-" && &date[10..11] == "T");
        assert!(p["machine"]["logical_cpus"].as_u64().unwrap() >= 1);
        assert!(!p["machine"]["os"].as_str().unwrap().is_empty());
        // The workspace is a git checkout: a 40-hex-digit commit, perhaps dirty.
        if let Some(c) = p["commit"].as_str() {
            let hash = c.trim_end_matches("-dirty");
            assert_eq!(hash.len(), 40, "{c}");
            assert!(hash.chars().all(|c| c.is_ascii_hexdigit()));
        }
    }
}
