//! The one place that knows which compiled copies of the hot loops the CPU can run. The row
//! tracer (`render::sample_row`), the light tracer's chunks (`CausticTracer::trace_pass`) and the
//! sphere lanes (`accel::lanes`) each have a copy compiled for x86-64-v3 ([`v3_copy!`]), chosen
//! at run time by [`ShadingCode::detect`] so the default build still runs on any x86-64; the
//! sphere lanes have an AVX-512F copy too ([`avx512_copy!`], [`has_avx512f`]), whose 8-wide f64
//! vectors fit their eight lanes. Rust never contracts a multiply and an add into an FMA, so every
//! copy gives the same bits. (`multiversion` was considered: its 0.7 and later releases do not
//! take methods with `self`, which every copy here is.)

/// Defines a function compiled for x86-64-v3 (only on x86-64): the features named here are the
/// ones [`ShadingCode::detect`] checks, so the two lists live side by side. Call it only when
/// `detect` returns [`ShadingCode::V3`].
macro_rules! v3_copy {
    ($(#[$meta:meta])* $vis:vis unsafe fn $($rest:tt)*) => {
        $(#[$meta])*
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
        $vis unsafe fn $($rest)*
    };
}
pub(crate) use v3_copy;

/// Defines a function compiled for AVX-512F (only on x86-64). Call it only when [`has_avx512f`]
/// returns true.
macro_rules! avx512_copy {
    ($(#[$meta:meta])* $vis:vis unsafe fn $($rest:tt)*) => {
        $(#[$meta])*
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        $vis unsafe fn $($rest)*
    };
}
pub(crate) use avx512_copy;

/// Whether this CPU runs [`avx512_copy!`] functions (detected once).
pub fn has_avx512f() -> bool {
    static HAS: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *HAS.get_or_init(|| {
        #[cfg(target_arch = "x86_64")]
        {
            std::arch::is_x86_feature_detected!("avx512f")
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    })
}

/// Which compiled copy of the hot loops (`render::sample_row`, the light tracer's chunks) this
/// CPU runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingCode {
    /// x86-64-v3: AVX2, FMA, BMI1/2, LZCNT, POPCNT.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    V3,
    /// What the build targets (x86-64's SSE2 without a `target-cpu`).
    Portable,
}

impl ShadingCode {
    /// The best copy this CPU can run (detected once).
    pub fn detect() -> Self {
        static CODE: std::sync::OnceLock<ShadingCode> = std::sync::OnceLock::new();
        *CODE.get_or_init(|| {
            #[cfg(target_arch = "x86_64")]
            {
                use std::arch::is_x86_feature_detected as has;
                // The features `v3_copy!` compiles for.
                let v3 = has!("avx2")
                    && has!("fma")
                    && has!("bmi1")
                    && has!("bmi2")
                    && has!("lzcnt")
                    && has!("popcnt");
                if v3 {
                    return ShadingCode::V3;
                }
            }
            ShadingCode::Portable
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            ShadingCode::V3 => "x86-64-v3",
            ShadingCode::Portable => "portable",
        }
    }
}
