//! Which debug views (`crate::viz`) the viewport shows: the selected
//! pixel's overlay, the whole image's, and the BVH level it draws.

use crate::viz::{image_views, View, PIXEL_VIEWS};

/// The overlays chosen, none at the start.
#[derive(Default)]
pub(crate) struct Overlays {
    /// The selected pixel's overlay drawn into the view (`o` cycles them).
    pub(crate) pixel: Option<View>,
    /// The view of the whole image over the viewport or in its place (`g`
    /// cycles them).
    pub(crate) image: Option<View>,
    /// The BVH level whose boxes `g` shows (`.` and `,` change it).
    level: usize,
}

impl Overlays {
    /// The next pixel overlay, or none after the last.
    pub(crate) fn next_pixel(&mut self) -> Option<View> {
        self.pixel = View::next(&PIXEL_VIEWS, self.pixel);
        self.pixel
    }

    /// The next image view, or none after the last.
    pub(crate) fn next_image(&mut self) -> Option<View> {
        self.image = View::next(&image_views(self.level), self.image);
        self.image
    }

    /// Moves `steps` levels in a BVH `depth` levels deep and shows that
    /// level's boxes.
    pub(crate) fn move_level(&mut self, steps: i8, depth: usize) -> Option<View> {
        let max = depth.saturating_sub(1) as i64;
        self.level = (self.level as i64 + steps as i64).clamp(0, max) as usize;
        self.image = Some(View::Level(self.level));
        self.image
    }

    /// Keeps the level inside a rebuilt BVH `depth` levels deep.
    pub(crate) fn fit_level(&mut self, depth: usize) {
        self.level = self.level.min(depth.saturating_sub(1));
    }
}
