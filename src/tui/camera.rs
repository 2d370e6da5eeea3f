//! The TUI's camera: the view the user moves, and the one it started from.

use crate::scene::Camera;

/// Camera orbit step per key press, in radians (5 degrees).
const ORBIT_STEP: f32 = 0.087_266_46;
/// Camera move step per key press, as a fraction of the initial eye-target distance.
const MOVE_STEP: f32 = 0.05;
/// Field-of-view step per key press, in degrees, and its limits.
const FOV_STEP: f32 = 5.0;
const FOV_RANGE: (f32, f32) = (5.0, 150.0);

#[derive(Clone, Copy, Debug)]
pub struct CameraControl {
    home: Camera,
    pub camera: Camera,
    /// World distance of one move step.
    step: f32,
}

impl CameraControl {
    pub fn new(home: Camera) -> Self {
        Self {
            home,
            camera: home,
            step: MOVE_STEP * (home.eye - home.target).length().max(1e-6),
        }
    }

    /// The camera the TUI started with.
    pub fn home(&self) -> Camera {
        self.home
    }

    /// Orbits by whole steps of yaw and pitch about the target.
    pub fn orbit(&mut self, yaw: i8, pitch: i8) {
        self.camera
            .orbit(yaw as f32 * ORBIT_STEP, pitch as f32 * ORBIT_STEP);
    }

    /// Moves by whole steps right, up and forward.
    pub fn pan(&mut self, right: i8, up: i8, forward: i8) {
        let s = self.step;
        self.camera
            .pan(right as f32 * s, up as f32 * s, forward as f32 * s);
    }

    /// Widens the field of view by whole steps (negative zooms in); returns it.
    pub fn zoom(&mut self, steps: i8) -> f32 {
        self.camera.vfov =
            (self.camera.vfov + steps as f32 * FOV_STEP).clamp(FOV_RANGE.0, FOV_RANGE.1);
        self.camera.vfov
    }

    pub fn reset(&mut self) {
        self.camera = self.home;
    }
}
