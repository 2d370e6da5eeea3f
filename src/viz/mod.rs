//! Every debug view in one place: [`View`] names them, and each view's
//! file holds its drawing and its legend: the BVH's boxes (`boxes`) and
//! heat maps (`heat`, with the heat colour map) over the image; bloom,
//! samples and error per pixel (`bloom`, `spp`, `error`) in place of it,
//! from the film; one pixel's ray tree (`pixel`). `draw` is the drawing kit
//! they share, `spec` what `--debug` asks for. `rayterm render --debug`
//! and the TUI draw the same views through the functions here.

pub mod bloom;
mod boxes;
pub mod draw;
mod error;
pub mod heat;
pub mod pixel;
mod spec;
mod spp;
mod view;

use anyhow::{bail, Result};
use glam::Vec3;

use crate::raster::canvas::Canvas;
use crate::render::{post, Film, Progressive, Tracer};
use crate::scene::BloomSettings;
use draw::{Layer, Legend};
pub use spec::DebugSpec;
pub use view::View;
pub(crate) use view::{image_views, DrawnFrom, PIXEL_VIEWS};

/// A view of the BVH drawn at the tracer's resolution, and what it shows in
/// words.
pub(crate) struct DebugImage {
    /// Linear RGB, row-major.
    pub(crate) image: Vec<Vec3>,
    pub(crate) summary: String,
}

/// `view`, a view of the BVH, as a layer over the tracer's image (box
/// outlines, or the heat map with its legend covering everything), and what
/// it shows in words.
pub(crate) fn layer(tracer: &Tracer, view: View) -> Result<(Layer, String)> {
    let mut layer = Canvas::new(tracer.width, tracer.height, None);
    let summary = match view {
        View::Heat(measure) => heat::draw(&mut layer, tracer, measure),
        View::Level(k) => boxes::level(&mut layer, tracer, k)?,
        View::Leaves => boxes::leaves(&mut layer, tracer),
        _ => bail!("{view} is not a view of the BVH"),
    };
    Ok((layer, summary))
}

/// Draws `view`, a view of the BVH, over one shaded sample per pixel (with
/// bloom where the plan has it).
pub(crate) fn draw(tracer: &Tracer, view: View) -> Result<DebugImage> {
    let (layer, summary) = layer(tracer, view)?;
    if let Some(image) = layer.pixels.iter().copied().collect::<Option<Vec<Vec3>>>() {
        // The heat map covers every pixel: nothing to render under it.
        return Ok(DebugImage { image, summary });
    }
    let film = Progressive::render(tracer, 1);
    let settings = &tracer.scene.settings.bloom;
    let (w, h) = (tracer.width, tracer.height);
    let mut image = post::display(film.image(), w, h, tracer.plan, settings).image;
    layer.over(&mut image);
    Ok(DebugImage { image, summary })
}

/// `view`, a view of the film, of `film` (`mean` its `width x height` mean
/// image): the picture shown in place of the image, and its legend.
/// `bloom_on` is whether the plan has bloom, which the bloom view notes
/// when not, naming the plan `whose`.
pub(crate) fn film_view(
    view: View,
    film: &Film,
    mean: &[Vec3],
    (width, height): (u32, u32),
    bloom: &BloomSettings,
    (bloom_on, whose): (bool, &str),
) -> Result<(Vec<Vec3>, Legend)> {
    Ok(match view {
        View::Bloom => {
            let (image, mut legend) = bloom::bloom_view(mean, width, height, bloom);
            if !bloom_on {
                legend.push((None, format!("bloom is off in {whose} plan")));
            }
            (image, legend)
        }
        View::Spp => spp::spp_view(film),
        View::Error => error::error_view(film),
        _ => bail!("{view} is not a view of the film"),
    })
}
