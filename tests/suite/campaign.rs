//! How the property tests choose their cases.
//!
//! By default every property runs the cases of its test file's committed
//! `.proptest-regressions` file, then a fixed number of cases from a fixed
//! seed: the same cases on every run and every machine, and a failure
//! writes nothing (it prints the line to add to the regressions file).
//!
//! `RAYTERM_CAMPAIGN=CASES` runs a randomized campaign instead: a fresh
//! seed each run and `CASES` cases per property (the committed regressions
//! first, as always), and every counterexample found is appended to the
//! regressions file, to be committed with a comment saying what it caught.
//! Run one before calling a change to traversal or the triangle test done
//! (CONTRIBUTING.md).

use std::any::Any;
use std::fmt::Debug;

use proptest::test_runner::{
    Config, FailurePersistence, FileFailurePersistence, PersistedSeed, RngSeed,
};

/// The regressions file beside each test file: `tests/suite/NAME.proptest-regressions`.
const FILE: FileFailurePersistence = FileFailurePersistence::WithSource("proptest-regressions");

/// The seed of the default cases. Changing it changes which cases run.
const SEED: u64 = 0x7261_7974_6572_6d33;

/// The configuration of a property with `cases` cases by default.
pub fn config(cases: u32) -> Config {
    match campaign() {
        Some(n) => Config {
            cases: n,
            rng_seed: RngSeed::Random,
            failure_persistence: Some(Box::new(FILE)),
            ..Config::default()
        },
        None => Config {
            cases,
            rng_seed: RngSeed::Fixed(SEED),
            failure_persistence: Some(Box::new(ReadOnly)),
            ..Config::default()
        },
    }
}

/// The cases per property of a campaign, when `RAYTERM_CAMPAIGN` asks for one.
fn campaign() -> Option<u32> {
    let v = std::env::var("RAYTERM_CAMPAIGN").ok()?;
    match v.trim().parse() {
        Ok(n) if n > 0 => Some(n),
        _ => panic!("RAYTERM_CAMPAIGN={v:?}: give the cases per property, a whole number above 0"),
    }
}

/// Reads the committed regressions; never writes them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ReadOnly;

impl FailurePersistence for ReadOnly {
    fn load_persisted_failures2(&self, source_file: Option<&'static str>) -> Vec<PersistedSeed> {
        FILE.load_persisted_failures2(source_file)
    }

    fn save_persisted_failure2(
        &mut self,
        source_file: Option<&'static str>,
        seed: PersistedSeed,
        shrunken: &dyn Debug,
    ) {
        let file = source_file.map_or("the test file".into(), |f| {
            std::path::Path::new(f)
                .with_extension("proptest-regressions")
                .display()
                .to_string()
        });
        eprintln!(
            "proptest: a new counterexample; to keep it, add this line to {file} \
             (with what it caught after the #):\n{seed} # {}",
            format!("{shrunken:?}").replace('\n', " ")
        );
    }

    fn box_clone(&self) -> Box<dyn FailurePersistence> {
        Box::new(*self)
    }

    fn eq(&self, other: &dyn FailurePersistence) -> bool {
        other.as_any().is::<ReadOnly>()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}
