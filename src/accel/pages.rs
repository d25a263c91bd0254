//! Transparent huge pages for the large arrays traversal reads (`madvise(MADV_HUGEPAGE)`).
//!
//! A walk of a big mesh touches nodes and triangles scattered over a hundred megabytes or
//! more; on 4 KiB pages nearly every visit also misses the TLB. Where the kernel hands out
//! huge pages only on request (`/sys/kernel/mm/transparent_hugepage/enabled` = `madvise`, a
//! common default), asking for them on these arrays measured (kitten subdivided 3 times,
//! 1.3M triangles, the system switch set to `always` against `madvise`, two alternating
//! runs each): BVH build 0.90x the time, packet8 / wide1 traversal 1.01-1.09x as fast. Where
//! huge pages are `always` or `never` this changes nothing; elsewhere than Linux it does
//! nothing.
//!
//! Also [`keep_freed_memory`], for the command line: freed memory kept for reuse rather
//! than handed back to the kernel and faulted in again.
//!
//! One of the crate's four `unsafe` places (the others: `packet16`'s AVX-512 dispatch,
//! `wide1::interleave`'s prefetch hint and AVX-512 VL dispatch, and
//! `io::output::writeback`'s request), kept to the system calls.

/// Arrays smaller than this stay on small pages (a huge page is 2 MiB).
const MIN_BYTES: usize = 4 << 20;

/// Ask for huge pages under `v`'s allocation (its capacity, not just its length), before it
/// is filled: pages first touched afterwards come as huge pages where the kernel has them. A
/// hint only: contents and behaviour are unchanged, and a refusal is ignored.
pub fn advise_huge<T>(v: &Vec<T>) {
    #[cfg(target_os = "linux")]
    {
        let bytes = v.capacity() * size_of::<T>();
        if bytes < MIN_BYTES {
            return;
        }
        const PAGE: usize = 4096;
        let start = (v.as_ptr() as usize).next_multiple_of(PAGE);
        let end = (v.as_ptr() as usize + bytes) & !(PAGE - 1);
        if end > start {
            #[allow(unsafe_code)]
            // SAFETY: the range [start, end) lies inside `v`'s live allocation (page-aligned
            // inward), and MADV_HUGEPAGE only changes how the kernel backs those pages: it
            // neither frees, moves nor alters their contents, so no reference into `v` is
            // invalidated. The return value is a hint's refusal and is ignored.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v;
}

/// Keep the memory the process frees for its own reuse. glibc's allocator hands blocks of
/// 128 KiB and more back to the kernel when they are freed (and trims the top of its heap),
/// so the next allocation of that size faults every page in again, zeroed by the kernel; a
/// render frees and allocates its tiles' pixels, its row batches and its compressed EXR
/// blocks every few megabytes. With blocks up to 32 MiB taken from the heap and the heap
/// trimmed only past 512 MiB free, they are reused. Measured 2026-12-07 (AMD EPYC Zen 5,
/// whole process, against the build without it, alternating runs): `cubemap` 1080p on one
/// thread 17.2k page faults -> 11.8k, system time 0.060 -> 0.043 s, CPU 0.97x (11 pairs);
/// `phong` 1080p 1.01x (level); `phong` 4K on two threads system time 0.067 -> 0.040 s,
/// wall 0.97x (7 pairs). For programs (the
/// `whitted` command calls it first): a library should not retune its host's allocator.
/// Whether the allocator took both settings (`false` off glibc, where it does nothing).
pub fn keep_freed_memory() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        #[allow(unsafe_code)]
        // SAFETY: `mallopt` sets two of glibc's allocator thresholds (it takes the
        // allocator's lock, so any thread may call it at any time); it touches no memory of
        // ours and every allocation stays valid.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20) == 1
                && libc::mallopt(libc::M_TRIM_THRESHOLD, 512 << 20) == 1
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The calling thread's minor page faults so far (`/proc/thread-self/stat`, field 10).
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    fn minor_faults() -> u64 {
        let stat = std::fs::read_to_string("/proc/thread-self/stat").unwrap();
        // the fields after the command name, which ends at the last ')'
        let rest = &stat[stat.rfind(')').unwrap() + 2..];
        rest.split(' ').nth(7).unwrap().parse().unwrap()
    }

    /// Once freed memory is kept, 8 MiB freed in blocks of 100 KiB (below glibc's first
    /// threshold, so from the heap, which it would then trim) come back without faulting
    /// their 2,000 pages in again (without the settings: about 1,970 faults).
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[test]
    fn freed_memory_is_reused_without_page_faults() {
        assert!(keep_freed_memory());
        let blocks = || -> Vec<Vec<u8>> { (0..80).map(|k| vec![k as u8; 100 << 10]).collect() };
        drop(std::hint::black_box(blocks()));
        let before = minor_faults();
        let again = std::hint::black_box(blocks());
        let faults = minor_faults() - before;
        assert_eq!(again[79][5], 79);
        assert!(
            faults < 200,
            "{faults} page faults for 8 MiB freed and allocated again"
        );
    }

    /// Contents survive the advice, small arrays are left alone, and where the kernel offers
    /// huge pages on request, a large advised array's mapping carries the advice (`hg` in its
    /// smaps `VmFlags`; whether huge pages then back it is the kernel's choice, reported).
    #[test]
    fn advised_arrays_keep_their_contents_and_carry_the_advice() {
        let small: Vec<u32> = (0..1000).collect();
        advise_huge(&small);
        assert!(small.iter().enumerate().all(|(i, &v)| v as usize == i));

        let n = 16 << 20; // 64 MiB of u32
        let mut big: Vec<u32> = Vec::with_capacity(n);
        advise_huge(&big);
        big.extend(0..n as u32);
        assert!(big.iter().enumerate().all(|(i, &v)| v as usize == i));

        let mode = std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled");
        if !mode.is_ok_and(|m| m.contains("[madvise]")) {
            println!("huge pages not given on request here; contents checked only");
            return;
        }
        // the mapping that holds the middle of `big` (the advice splits the allocation's
        // mapping at its first whole page).
        let addr = &big[n / 2] as *const u32 as usize;
        let smaps = std::fs::read_to_string("/proc/self/smaps").unwrap();
        let mut inside = false;
        let (mut flags, mut huge) = (String::new(), String::new());
        for line in smaps.lines() {
            if let Some((range, _)) = line.split_once(' ')
                && let Some((a, b)) = range.split_once('-')
                && let (Ok(a), Ok(b)) = (usize::from_str_radix(a, 16), usize::from_str_radix(b, 16))
            {
                inside = (a..b).contains(&addr);
            } else if inside && let Some(f) = line.strip_prefix("VmFlags:") {
                flags = f.to_string();
            } else if inside && let Some(kb) = line.strip_prefix("AnonHugePages:") {
                huge = kb.trim().to_string();
            }
        }
        println!("advised mapping: AnonHugePages {huge}, VmFlags{flags}");
        assert!(
            flags.split_whitespace().any(|f| f == "hg"),
            "the advised array's mapping has no huge-page advice: VmFlags{flags}"
        );
    }
}
