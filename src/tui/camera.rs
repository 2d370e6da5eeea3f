//! The TUI's camera: the view the user moves, and the one it started from.

use crate::scene::{Camera, Projection};

/// Camera orbit step per key press, in radians (5 degrees).
const ORBIT_STEP: f32 = 0.087_266_46;
/// Camera move step per key press, as a fraction of the initial eye-target distance.
const MOVE_STEP: f32 = 0.05;
/// Field-of-view step per key press, in degrees, and its limits.
const FOV_STEP: f32 = 5.0;
const FOV_RANGE: (f32, f32) = (5.0, 150.0);
/// An orthographic view's height grows by this factor per key press, up
/// to this many times larger or smaller than it started.
const HEIGHT_STEP: f32 = 1.1;
const HEIGHT_RANGE: f32 = 64.0;

#[derive(Clone, Copy, Debug)]
pub(crate) struct CameraControl {
    home: Camera,
    pub(crate) camera: Camera,
    /// World distance of one move step.
    step: f32,
}

impl CameraControl {
    pub(crate) fn new(home: Camera) -> Self {
        Self {
            home,
            camera: home,
            step: MOVE_STEP * (home.eye - home.target).length().max(1e-6),
        }
    }

    /// Orbits by whole steps of yaw and pitch about the target.
    pub(crate) fn orbit(&mut self, yaw: i8, pitch: i8) {
        self.camera
            .orbit(yaw as f32 * ORBIT_STEP, pitch as f32 * ORBIT_STEP);
    }

    /// Moves by whole steps right, up and forward.
    pub(crate) fn pan(&mut self, right: i8, up: i8, forward: i8) {
        let s = self.step;
        self.camera
            .pan(right as f32 * s, up as f32 * s, forward as f32 * s);
    }

    /// Widens the view by whole steps (negative zooms in): the field of
    /// view, or an orthographic view's height (moving an orthographic
    /// camera forward only moves the plane its rays start from); returns
    /// the projection.
    pub(crate) fn zoom(&mut self, steps: i8) -> Projection {
        self.camera.projection = match (self.camera.projection, self.home.projection) {
            (Projection::Perspective { vfov }, _) => Projection::Perspective {
                vfov: (vfov + steps as f32 * FOV_STEP).clamp(FOV_RANGE.0, FOV_RANGE.1),
            },
            (Projection::Orthographic { half_height: h }, home) => {
                let home = match home {
                    Projection::Orthographic { half_height } => half_height,
                    Projection::Perspective { .. } => h,
                };
                Projection::Orthographic {
                    half_height: (h * HEIGHT_STEP.powi(steps as i32))
                        .clamp(home / HEIGHT_RANGE, home * HEIGHT_RANGE),
                }
            }
        };
        self.camera.projection
    }

    pub(crate) fn reset(&mut self) {
        self.camera = self.home;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn control(projection: Projection) -> CameraControl {
        CameraControl::new(Camera {
            eye: Vec3::Z,
            target: Vec3::ZERO,
            up: Vec3::Y,
            projection,
        })
    }

    #[test]
    fn zoom_narrows_a_field_of_view_and_shrinks_an_orthographic_view() {
        let mut c = control(Projection::perspective(45.0));
        assert_eq!(c.zoom(-1), Projection::perspective(40.0));
        assert_eq!(c.zoom(100), Projection::perspective(FOV_RANGE.1));
        let mut c = control(Projection::Orthographic { half_height: 2.0 });
        let Projection::Orthographic { half_height: h } = c.zoom(-1) else {
            panic!("the projection changed");
        };
        assert!((h - 2.0 / HEIGHT_STEP).abs() < 1e-6, "{h}");
        let Projection::Orthographic { half_height: h } = c.zoom(3) else {
            panic!("the projection changed");
        };
        assert!((h - 2.0 * HEIGHT_STEP * HEIGHT_STEP).abs() < 1e-5, "{h}");
        assert_eq!(
            c.zoom(127),
            Projection::Orthographic {
                half_height: 2.0 * HEIGHT_RANGE
            }
        );
        c.reset();
        assert_eq!(
            c.camera.projection,
            Projection::Orthographic { half_height: 2.0 }
        );
    }
}
