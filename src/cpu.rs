//! The SIMD level compiled in beside the CPU's, and a one-time warning when they disagree.
//!
//! whitted's kernels are written for 8-wide `f32` SIMD, which is one AVX register when the
//! crate is compiled for x86-64-v3 (the project's `.cargo/config.toml`). A crate that depends
//! on whitted does not read that file, and gets the x86-64 baseline (SSE2): every 8-wide
//! operation becomes two 4-wide ones and the engines run about 2x slower, silently.
//! [`warn_if_slow_build`] says so once per process.

use std::sync::Once;

/// Feature names in the order [`compiled_features`] and [`cpu_features`] list them.
const FEATURES: [&str; 5] = ["sse4.2", "avx", "avx2", "fma", "avx512f"];

/// The x86 SIMD features this build of whitted was compiled with (`-C target-cpu` /
/// `target-feature`), among SSE4.2, AVX, AVX2, FMA and AVX-512F. The AVX-512 kernels
/// (`accel::packet16`) are compiled for AVX-512 on their own and chosen at run time whatever
/// this says.
pub fn compiled_features() -> Vec<&'static str> {
    let on = [
        cfg!(target_feature = "sse4.2"),
        cfg!(target_feature = "avx"),
        cfg!(target_feature = "avx2"),
        cfg!(target_feature = "fma"),
        cfg!(target_feature = "avx512f"),
    ];
    FEATURES
        .into_iter()
        .zip(on)
        .filter_map(|(f, on)| on.then_some(f))
        .collect()
}

/// The same features, as the CPU running this process has them.
pub fn cpu_features() -> Vec<&'static str> {
    #[cfg(target_arch = "x86_64")]
    let on = [
        std::arch::is_x86_feature_detected!("sse4.2"),
        std::arch::is_x86_feature_detected!("avx"),
        std::arch::is_x86_feature_detected!("avx2"),
        std::arch::is_x86_feature_detected!("fma"),
        std::arch::is_x86_feature_detected!("avx512f"),
    ];
    #[cfg(not(target_arch = "x86_64"))]
    let on = [false; 5];
    FEATURES
        .into_iter()
        .zip(on)
        .filter_map(|(f, on)| on.then_some(f))
        .collect()
}

/// The highest level among `features`: `"x86-64-v4"` (AVX-512F), `"x86-64-v3"` (AVX2 and
/// FMA), `"avx"`, `"sse4.2"` or `"x86-64"` (the baseline).
pub fn level(features: &[&str]) -> &'static str {
    let has = |f: &str| features.contains(&f);
    if has("avx512f") && has("avx2") {
        "x86-64-v4"
    } else if has("avx2") && has("fma") {
        "x86-64-v3"
    } else if has("avx") {
        "avx"
    } else if has("sse4.2") {
        "sse4.2"
    } else {
        "x86-64"
    }
}

/// The warning, when the CPU has AVX2 and this build of whitted lacks it; else `None`.
pub fn slow_build_warning() -> Option<String> {
    let compiled = cfg!(target_feature = "avx2");
    let cpu = cpu_features().contains(&"avx2");
    (cpu && !compiled).then(|| {
        "whitted was compiled without AVX2 but this CPU has it: the 8-wide kernels run as \
         two SSE halves, about 2x slower. Build with RUSTFLAGS=\"-C target-cpu=x86-64-v3\" \
         (whitted's own .cargo/config.toml does this for builds inside its repository)."
            .to_string()
    })
}

/// [`slow_build_warning`] the first time this or [`warn_if_slow_build`] is called in the
/// process, `None` after: for front ends that give the warning their own way (the Python
/// module turns it into a Python `RuntimeWarning`).
pub fn take_slow_build_warning() -> Option<String> {
    static ONCE: Once = Once::new();
    let mut out = None;
    ONCE.call_once(|| out = slow_build_warning());
    out
}

/// Print [`slow_build_warning`] to stderr, at most once per process (and not after
/// [`take_slow_build_warning`] took it). The command line calls it at start-up and
/// [`World::new`](crate::world::World::new) before building a BVH.
pub fn warn_if_slow_build() {
    if let Some(w) = take_slow_build_warning() {
        eprintln!("warning: {w}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_and_the_warning_follow_the_features() {
        assert_eq!(
            level(&["sse4.2", "avx", "avx2", "fma", "avx512f"]),
            "x86-64-v4"
        );
        assert_eq!(level(&["sse4.2", "avx", "avx2", "fma"]), "x86-64-v3");
        assert_eq!(level(&["sse4.2"]), "sse4.2");
        assert_eq!(level(&[]), "x86-64");
        // every compiled feature runs on this CPU (else the tests would not run at all)
        let cpu = cpu_features();
        assert!(compiled_features().iter().all(|f| cpu.contains(f)));
        assert_eq!(
            slow_build_warning().is_some(),
            cpu.contains(&"avx2") && !compiled_features().contains(&"avx2")
        );
        take_slow_build_warning();
        assert_eq!(take_slow_build_warning(), None);
        warn_if_slow_build();
    }
}
