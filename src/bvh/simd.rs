//! Which SIMD instructions the walks use: the widest this CPU has, found at
//! run time, or a narrower one asked for to compare the two on the same
//! machine (`rayterm bench rays --simd`).

use crate::choice::Choice;

/// The kernels of a walk, narrowest first.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Simd {
    #[default]
    Portable,
    Avx,
    Avx512,
}

impl Choice for Simd {
    const ALL: &'static [Self] = &[Simd::Portable, Simd::Avx, Simd::Avx512];

    fn choice(self) -> (&'static str, &'static str) {
        let help = match self {
            Simd::Portable => "Four lanes of SSE (or whatever the target has), on any CPU",
            Simd::Avx => "Eight lanes of AVX",
            Simd::Avx512 => {
                "The AVX kernels compiled for AVX-512 (F, VL, DQ, BW): 32 vector registers, eight lanes"
            }
        };
        (self.name(), help)
    }
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

    /// This level, where this CPU runs it; else an error naming the
    /// widest it has.
    pub(crate) fn on_this_cpu(self) -> anyhow::Result<Simd> {
        let most = Simd::detect();
        if self > most {
            anyhow::bail!("--simd {self}: this CPU has no {self} (the widest it has is {most})");
        }
        Ok(self)
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

/// A level this CPU runs: made only from [`Simd::detect`], so a walk may
/// call the kernels compiled for it. The default is the portable level,
/// which every CPU runs.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Detected(Simd);

impl Detected {
    /// The widest level this CPU runs, or `most` if narrower.
    pub(super) fn at_most(most: Simd) -> Self {
        Detected(Simd::detect().min(most))
    }

    pub(super) fn level(self) -> Simd {
        self.0
    }

    /// The AVX kernels, where this level has them.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(super) fn avx(self) -> Option<Avx> {
        (self.0 >= Simd::Avx).then_some(Avx(()))
    }
}

/// The AVX kernels (eight lanes at a time): made only by [`Detected::avx`],
/// so one exists only where the CPU has AVX.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(super) struct Avx(());
