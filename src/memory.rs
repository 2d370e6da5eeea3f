//! Memory checks before large allocations: a small file can ask for a lot
//! (a patch file tessellated at 1024 segments, a compressed texture), so
//! the loaders compute what a request needs first and refuse it, saying how
//! much, when it cannot fit.
//!
//! The budget is what the system says is available (`MemAvailable` in
//! `/proc/meminfo`), or less where the process's control group has a
//! memory limit (a container's, a batch job's) or the process an address
//! space limit (`ulimit -v`), read when the check is made; where none can
//! be read a fixed [`FALLBACK`] stands in. A request needing more would end
//! in the out-of-memory killer or an allocation abort, never in a picture.

use std::path::Path;

use anyhow::{bail, Result};

/// Peak memory per triangle of a loaded, built and rendered scene: 193
/// bytes measured (`/usr/bin/time rayterm render teapot:256`: tessellation,
/// scene arrays, BVH build; 182 for a 2-million-triangle OBJ grid), rounded
/// up.
pub(crate) const BYTES_PER_TRIANGLE: u64 = 200;

/// Peak memory per vertex beyond one a triangle (which
/// [`BYTES_PER_TRIANGLE`] counts: meshes have about half as many vertices
/// as triangles): its position in f64 as placed and in f32, its normal,
/// texture coordinates and colour. Measured (`/usr/bin/time`, the file
/// itself left out): 52 bytes for a PLY of 20 million bare vertices, 68
/// for one of 4 million with normals, texture coordinates and colours;
/// rounded up.
pub(crate) const BYTES_PER_VERTEX: u64 = 72;

/// The budget where `/proc/meminfo` cannot be read.
pub(crate) const FALLBACK: u64 = 16 << 30;

/// Memory a mesh of `vertices` and `triangles` takes, loaded, built and
/// rendered.
pub(crate) fn mesh_bytes(vertices: u64, triangles: u64) -> u64 {
    let extra = vertices.saturating_sub(triangles);
    triangles
        .saturating_mul(BYTES_PER_TRIANGLE)
        .saturating_add(extra.saturating_mul(BYTES_PER_VERTEX))
}

/// What a scene being loaded may still take: the memory available when
/// its first mesh is read, less what the meshes read before it take once
/// built. Each mesh is checked against the room the others leave, so the
/// scene as a whole fits before anything of it is built.
#[derive(Debug, Default)]
pub(crate) struct Budget {
    available: Option<u64>,
    taken: u64,
}

impl Budget {
    /// The bytes left for the next mesh.
    pub(crate) fn room(&mut self) -> u64 {
        self.available
            .get_or_insert_with(available)
            .saturating_sub(self.taken)
    }

    /// Counts a mesh read.
    pub(crate) fn take(&mut self, vertices: u64, triangles: u64) {
        self.taken = self.taken.saturating_add(mesh_bytes(vertices, triangles));
    }
}

/// Memory available for new allocations, in bytes: the system's, or the
/// room the control group's limit or the address space limit leaves where
/// that is less.
pub(crate) fn available() -> u64 {
    let system = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("MemAvailable:"))
                .and_then(|v| v.trim().strip_suffix("kB"))
                .and_then(|v| v.trim().parse::<u64>().ok())
        })
        .map(|kib| kib.saturating_mul(1024));
    let group = std::fs::read_to_string("/proc/self/cgroup")
        .ok()
        .and_then(|c| cgroup_room(&c, Path::new("/sys/fs/cgroup")));
    [system, group, address_room()]
        .into_iter()
        .flatten()
        .min()
        .unwrap_or(FALLBACK)
}

/// The room the address space limit (`RLIMIT_AS`, `ulimit -v`) leaves: the
/// limit less the address space in use (`VmSize` in `/proc/self/status`),
/// where one is set. Past it, an allocation fails and the process aborts.
fn address_room() -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the limit into the struct it is given.
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } != 0
        || limit.rlim_cur == libc::RLIM_INFINITY
    {
        return None;
    }
    let used = std::fs::read_to_string("/proc/self/status")
        .ok()?
        .lines()
        .find_map(|l| l.strip_prefix("VmSize:"))
        .and_then(|v| v.trim().strip_suffix("kB"))
        .and_then(|v| v.trim().parse::<u64>().ok())?
        .saturating_mul(1024);
    Some(limit.rlim_cur.saturating_sub(used))
}

/// The room the memory limits of a control group leave: the least, over
/// the process's group and the groups above it, of the limit less the
/// memory in use (less what the kernel can drop at once, the inactive file
/// cache). `cgroups` is `/proc/self/cgroup`, `root` where the hierarchies
/// are mounted; a unified (v2) hierarchy has `memory.max`, a v1 memory
/// controller `memory/…/memory.limit_in_bytes`. `None` where no limit is
/// set or none can be read.
fn cgroup_room(cgroups: &str, root: &Path) -> Option<u64> {
    let (base, path, limit, usage, cache) = cgroups.lines().find_map(|l| {
        let mut f = l.splitn(3, ':');
        let (_, controllers, path) = (f.next()?, f.next()?, f.next()?);
        let path = path.trim_start_matches('/');
        match controllers {
            "" => Some((
                root.to_path_buf(),
                path,
                "memory.max",
                "memory.current",
                "inactive_file",
            )),
            c if c.split(',').any(|c| c == "memory") => Some((
                root.join("memory"),
                path,
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
                "total_inactive_file",
            )),
            _ => None,
        }
    })?;
    let number = |dir: &Path, file: &str| -> Option<u64> {
        std::fs::read_to_string(dir.join(file))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    let inactive = |dir: &Path| -> u64 {
        std::fs::read_to_string(dir.join("memory.stat"))
            .ok()
            .and_then(|s| {
                s.lines().find_map(|l| {
                    l.strip_prefix(cache)?
                        .strip_prefix(' ')?
                        .trim()
                        .parse()
                        .ok()
                })
            })
            .unwrap_or(0)
    };
    // In a container the group's path may name one outside the mounted
    // view, whose root is then the group itself.
    let mut dir = base.join(path);
    if !dir.is_dir() {
        dir = base.clone();
    }
    let mut room: Option<u64> = None;
    loop {
        // "max" (v2) does not parse; v1 says no limit with a huge number.
        if let (Some(limit), Some(used)) = (number(&dir, limit), number(&dir, usage)) {
            if limit < 1 << 60 {
                let here = limit.saturating_sub(used.saturating_sub(inactive(&dir)));
                room = Some(room.map_or(here, |r| r.min(here)));
            }
        }
        if dir == base || !dir.pop() {
            return room;
        }
    }
}

/// `n` values whose bytes are all zero, in fresh memory the kernel may
/// back with 2 MiB pages: its zeroed pages are the values, so nothing is
/// written until used, and a film of millions of pixels faults in a few
/// hundred pages rather than a hundred thousand.
///
/// All-zero bytes are a valid `T`: the compiler checks that through
/// `Zeroable`, derived field by field.
pub(crate) fn zeroed<T: bytemuck::Zeroable>(n: usize) -> Vec<T> {
    assert!(
        std::mem::size_of::<T>() > 0,
        "zero-sized values need no memory"
    );
    let Ok(layout) = std::alloc::Layout::array::<T>(n) else {
        panic!("{n} values cannot be held in memory");
    };
    if n == 0 {
        return Vec::new();
    }
    // SAFETY: the layout has a non-zero size (n > 0, T not zero-sized).
    let ptr = unsafe { std::alloc::alloc_zeroed(layout) };
    if ptr.is_null() {
        std::alloc::handle_alloc_error(layout);
    }
    advise_huge(ptr, layout.size());
    // SAFETY: the memory was allocated by the global allocator for exactly
    // `n` values of `T`, and zero bytes are a `T` (`Zeroable`).
    unsafe { Vec::from_raw_parts(ptr as *mut T, n, n) }
}

/// An empty vector with room for `n` values, in fresh memory the kernel may
/// back with 2 MiB pages: a large array filled once (a BVH's nodes, its
/// triangle packets) then faults in a few pages rather than thousands,
/// which on a virtual machine cost more than writing the values.
pub(crate) fn room<T>(n: usize) -> Vec<T> {
    let Ok(layout) = std::alloc::Layout::array::<T>(n) else {
        panic!("{n} values cannot be held in memory");
    };
    if layout.size() < HUGE {
        return Vec::with_capacity(n);
    }
    // SAFETY: the layout has a non-zero size; the vector takes the
    // allocation with that layout's capacity and no values.
    unsafe {
        let ptr = std::alloc::alloc(layout);
        if ptr.is_null() {
            std::alloc::handle_alloc_error(layout);
        }
        advise_huge(ptr, layout.size());
        Vec::from_raw_parts(ptr as *mut T, 0, n)
    }
}

/// A huge page's size.
const HUGE: usize = 2 << 20;

/// Asks the kernel to back the whole huge pages within `size` bytes from
/// `ptr` with huge pages.
fn advise_huge(ptr: *mut u8, size: usize) {
    #[cfg(target_os = "linux")]
    {
        let at = ptr as usize;
        let (start, end) = (at.next_multiple_of(HUGE), (at + size) & !(HUGE - 1));
        if end > start {
            // Only advice: where the kernel declines, small pages serve.
            // SAFETY: the range lies within one live allocation.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (ptr, size);
}

/// Refuses `needed` bytes for `what` when more than the memory available
/// (or than `cap`, a documented limit of its own, when given).
pub(crate) fn check(what: &str, needed: u64, cap: Option<(u64, &str)>) -> Result<()> {
    if let Some((cap, name)) = cap {
        if needed > cap {
            bail!(
                "{what} would need {} of memory, over the {} limit {name}",
                bytes(needed),
                bytes(cap)
            );
        }
    }
    let avail = available();
    if needed > avail {
        bail!(
            "{what} would need {} of memory; {} is available",
            bytes(needed),
            bytes(avail)
        );
    }
    Ok(())
}

/// A byte count in binary units, three significant digits: `1.5 GiB`.
pub(crate) fn bytes(n: u64) -> String {
    const UNITS: [&str; 6] = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut x = n as f64;
    let mut unit = 0;
    while x >= 1024.0 && unit + 1 < UNITS.len() {
        x /= 1024.0;
        unit += 1;
    }
    match unit {
        0 => format!("{n} bytes"),
        _ if x >= 100.0 => format!("{x:.0} {}", UNITS[unit]),
        _ if x >= 10.0 => format!("{x:.1} {}", UNITS[unit]),
        _ => format!("{x:.2} {}", UNITS[unit]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_read_well() {
        assert_eq!(bytes(12), "12 bytes");
        assert_eq!(bytes(1 << 30), "1.00 GiB");
        assert_eq!(bytes(2_600_000_000), "2.42 GiB");
        assert_eq!(bytes(25 << 30), "25.0 GiB");
        assert_eq!(bytes(u64::MAX), "16384 PiB");
    }

    #[test]
    fn room_holds_what_it_promises() {
        // Small (ordinary allocation), large (advised), aligned and empty.
        for n in [0, 3, (HUGE / 4) * 3 + 5] {
            let mut v: Vec<u32> = room(n);
            assert!(v.is_empty() && v.capacity() >= n, "{n}");
            let at = v.as_ptr();
            v.extend((0..n as u32).map(|i| i ^ 0x5a5a));
            assert_eq!(v.as_ptr(), at, "{n} values moved");
            assert!(v.iter().enumerate().all(|(i, &x)| x == i as u32 ^ 0x5a5a));
        }
        #[repr(align(32))]
        struct Wide([u8; 96]);
        let mut v: Vec<Wide> = room(HUGE / 32);
        assert_eq!(v.as_ptr() as usize % 32, 0);
        assert!(v.capacity() >= HUGE / 32);
        v.push(Wide([7; 96]));
        assert_eq!(v[0].0[95], 7);
    }

    /// Control groups' limits, v2 and v1, at the process's group and
    /// above it, with the inactive file cache counted as free.
    #[test]
    fn control_group_limits_bound_the_room() {
        let root = std::env::temp_dir().join(format!("rayterm-cgroup-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let write = |dir: &Path, files: &[(&str, &str)]| {
            std::fs::create_dir_all(dir).unwrap();
            for (name, text) in files {
                std::fs::write(dir.join(name), text).unwrap();
            }
        };
        let v2 = root.join("v2");
        write(
            &v2.join("job"),
            &[("memory.max", "max\n"), ("memory.current", "5\n")],
        );
        write(
            &v2.join("job/step"),
            &[
                ("memory.max", "1000\n"),
                ("memory.current", "700\n"),
                ("memory.stat", "anon 500\ninactive_file 200\n"),
            ],
        );
        assert_eq!(cgroup_room("0::/job/step\n", &v2), Some(500));
        assert_eq!(cgroup_room("0::/job\n", &v2), None, "no limit");
        write(
            &v2.join("job"),
            &[("memory.max", "300\n"), ("memory.current", "250\n")],
        );
        assert_eq!(cgroup_room("0::/job/step\n", &v2), Some(50), "the parent's");
        // A path outside the mounted view: the mount's root is the group.
        write(&v2, &[("memory.max", "4096\n"), ("memory.current", "96\n")]);
        assert_eq!(cgroup_room("0::/elsewhere\n", &v2), Some(4000));
        let v1 = root.join("v1");
        write(
            &v1.join("memory/slurm/job"),
            &[
                ("memory.limit_in_bytes", "2048\n"),
                ("memory.usage_in_bytes", "1000\n"),
                ("memory.stat", "cache 10\ntotal_inactive_file 24\n"),
            ],
        );
        write(
            &v1.join("memory"),
            &[
                ("memory.limit_in_bytes", "9223372036854771712\n"),
                ("memory.usage_in_bytes", "1\n"),
            ],
        );
        let v1_groups = "12:pids:/slurm/job\n4:cpu,memory:/slurm/job\n0::/\n";
        assert_eq!(cgroup_room(v1_groups, &v1), Some(1072));
        assert_eq!(cgroup_room("3:cpu:/x\n", &v1), None, "no memory controller");
        std::fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn refuses_more_than_there_is() {
        assert!(available() > 0);
        assert!(check("a small thing", 1 << 10, None).is_ok());
        let e = check("a huge thing", u64::MAX, None)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("a huge thing would need 16384 PiB"), "{e}");
        let e = check("a texture", 3 << 30, Some((2 << 30, "per texture")))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "a texture would need 3.00 GiB of memory, over the 2.00 GiB limit per texture"
        );
    }
}
