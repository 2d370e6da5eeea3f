//! Which SIMD instructions the walks use: the widest this CPU has, found at
//! run time, or a narrower one asked for to compare the two on the same
//! machine (`rayterm bench rays --simd`).

/// The kernels of a walk, narrowest first.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Simd {
    /// Four lanes of SSE (or whatever the target has), on any CPU.
    #[default]
    Portable,
    /// Eight lanes of AVX.
    Avx,
    /// The AVX kernels compiled for AVX-512 (F, VL, DQ, BW): 32 vector
    /// registers, eight lanes.
    Avx512,
}

impl Simd {
    /// The widest this CPU runs.
    pub fn detect() -> Simd {
        #[cfg(target_arch = "x86_64")]
        {
            use std::is_x86_feature_detected as has;
            if has!("avx512f")
                && has!("avx512vl")
                && has!("avx512dq")
                && has!("avx512bw")
                && has!("bmi1")
                && has!("popcnt")
            {
                return Simd::Avx512;
            }
            if has!("avx") {
                return Simd::Avx;
            }
        }
        Simd::Portable
    }

    /// Every level this CPU runs, narrowest first.
    pub fn available() -> Vec<Simd> {
        let most = Simd::detect();
        [Simd::Portable, Simd::Avx, Simd::Avx512]
            .into_iter()
            .filter(|&s| s <= most)
            .collect()
    }

    pub fn name(self) -> &'static str {
        match self {
            Simd::Portable => "portable",
            Simd::Avx => "avx",
            Simd::Avx512 => "avx512",
        }
    }
}

impl std::fmt::Display for Simd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
