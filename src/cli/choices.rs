//! The lower layers' [`Choice`]s as clap values: their names and help
//! lines, offered and parsed exactly as a derived `ValueEnum` would.

use clap::builder::PossibleValue;
use clap::ValueEnum;

use crate::bvh::Simd;
use crate::choice::Choice;
use crate::render::aov::Aov;
use crate::render::{Feature, Worst};
use crate::scene::{Builder, Integrator};
use crate::tui::color::ColorMode;
use crate::tui::graphics::symbols::SymbolsArg;
use crate::tui::graphics::GraphicsArg;

macro_rules! value_enum {
    ($($t:ty),* $(,)?) => {$(
        impl ValueEnum for $t {
            fn value_variants<'a>() -> &'a [Self] {
                <$t as Choice>::ALL
            }

            fn to_possible_value(&self) -> Option<PossibleValue> {
                let (name, help) = self.choice();
                Some(PossibleValue::new(name).help(help))
            }
        }
    )*};
}

value_enum!(
    Feature,
    Worst,
    Aov,
    Builder,
    Integrator,
    Simd,
    ColorMode,
    SymbolsArg,
    GraphicsArg
);
