//! The `--reference` image the true error is measured against, and the
//! view size the status line last said how to make it exact for.

use std::path::Path;
use std::sync::Arc;

use anyhow::Result;

use super::worker::{Reference, Snapshot, Truth};
use crate::raster::reference::load_reference;
use crate::render::Plan;
use crate::scene::Camera;

/// The reference, if one was given.
#[derive(Default)]
pub(crate) struct ReferenceImage {
    image: Option<Arc<Reference>>,
    /// The view size the resampling note was last given for.
    noted: Option<(u32, u32)>,
}

impl ReferenceImage {
    /// Loads the image at `path`, if any: the scene seen from `camera`
    /// with `plan`, the view the true error is shown at.
    pub(crate) fn load(path: Option<&Path>, camera: Camera, plan: &Plan) -> Result<Self> {
        let Some(path) = path else {
            return Ok(Self::default());
        };
        let (width, height, image) = load_reference(path)?;
        Ok(ReferenceImage {
            image: Some(Arc::new(Reference {
                name: path.display().to_string(),
                width,
                height,
                image,
                camera,
                plan: plan.clone(),
            })),
            noted: None,
        })
    }

    /// The image, shared with the worker that compares against it.
    pub(crate) fn shared(&self) -> Option<Arc<Reference>> {
        self.image.clone()
    }

    pub(crate) fn loaded(&self) -> bool {
        self.image.is_some()
    }

    /// What the status line says at the start: which image, and where.
    pub(crate) fn greeting(&self) -> String {
        match &self.image {
            Some(r) => format!(
                "Reference {} ({}x{}): the true error is shown at the start view (r returns to it).",
                r.name, r.width, r.height
            ),
            None => String::new(),
        }
    }

    /// Once per view size, how to render a reference that compares exactly
    /// with pass `f`: resampling it adds error wherever an edge falls
    /// inside a reference pixel.
    pub(crate) fn resampling_note(&mut self, f: &Snapshot) -> Option<String> {
        let (Truth::Compared { exact: false, .. }, Some(r)) = (f.truth, &self.image) else {
            return None;
        };
        if self.noted == Some((f.width, f.height)) {
            return None;
        }
        self.noted = Some((f.width, f.height));
        let k = ((r.width as f64 / f.width as f64).round() as u32).max(1);
        Some(format!(
            "For an exact true error render the reference at {}x{} ({k}x the {}x{} view): this {}x{} one is resampled, which adds error at edges.",
            k * f.width,
            k * f.height,
            f.width,
            f.height,
            r.width,
            r.height,
        ))
    }
}
