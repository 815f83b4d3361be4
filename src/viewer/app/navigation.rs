//! Where the explorer looks: the current view ([`Nav`]) with its back/forward history, and
//! the pointer gestures in progress (a wheel zoom, a box being drawn), with the image area
//! they are measured in.

use std::time::Instant;

use eframe::egui::{Pos2, Rect};

use crate::viewer::nav::{History, Nav};

/// The view, its history and the gestures that change it.
pub(super) struct Navigation {
    nav: Nav,
    history: History,
    /// Where a box zoom started.
    box_start: Option<Pos2>,
    /// When the wheel last turned (one history entry per wheel gesture).
    last_wheel: Option<Instant>,
    /// The image area (points), as last laid out.
    image_rect: Rect,
    /// The image area's size in physical pixels.
    size_px: [u32; 2],
}

impl Navigation {
    /// Looking at `nav`, with no history.
    pub(super) fn new(nav: Nav) -> Self {
        Self {
            nav,
            history: History::default(),
            box_start: None,
            last_wheel: None,
            image_rect: Rect::NOTHING,
            size_px: [0, 0],
        }
    }

    /// The current view.
    pub(super) fn nav(&self) -> &Nav {
        &self.nav
    }

    /// Views behind and ahead in the history.
    pub(super) fn history_lens(&self) -> (usize, usize) {
        self.history.lens()
    }

    /// Goes to `nav`, recording the current view in the history; true when the view moved.
    pub(super) fn go(&mut self, nav: Nav) -> bool {
        if nav == self.nav {
            return false;
        }
        self.history.push(self.nav.clone());
        self.nav = nav;
        true
    }

    /// Back in the history; true when the view moved.
    pub(super) fn back(&mut self) -> bool {
        self.history.back(self.nav.clone()).map(|n| self.nav = n).is_some()
    }

    /// Forward in the history; true when the view moved.
    pub(super) fn forward(&mut self) -> bool {
        self.history.forward(self.nav.clone()).map(|n| self.nav = n).is_some()
    }

    /// Zooms by `factor` about pixel `at` (from the image centre, y down); a wheel gesture
    /// (smoothed scrolling spans frames) makes one history entry.
    pub(super) fn wheel_zoom(&mut self, factor: f64, at: [f64; 2]) {
        if self.last_wheel.is_none_or(|t| t.elapsed().as_secs_f64() > 0.4) {
            self.history.push(self.nav.clone());
        }
        self.last_wheel = Some(Instant::now());
        self.nav = self.nav.zoom_about(factor, at, self.height());
    }

    /// Pans by (dx, dy) pixels; the first step of a drag makes a history entry.
    pub(super) fn drag_pan(&mut self, dx: f64, dy: f64, first: bool) {
        if first {
            self.history.push(self.nav.clone());
        }
        self.nav = self.nav.pan(dx, dy, self.height());
    }

    /// Lays the image area out at `rect`, `size_px` physical pixels; true when the size
    /// changed.
    pub(super) fn lay_out(&mut self, rect: Rect, size_px: [u32; 2]) -> bool {
        self.image_rect = rect;
        std::mem::replace(&mut self.size_px, size_px) != size_px
    }

    /// The image area (points).
    pub(super) fn image_rect(&self) -> Rect {
        self.image_rect
    }

    /// The image area's size in physical pixels (0 before the first layout).
    pub(super) fn size_px(&self) -> [u32; 2] {
        self.size_px
    }

    /// The image height in pixels, at least 1.
    pub(super) fn height(&self) -> f64 {
        self.size_px[1].max(1) as f64
    }

    /// Where the box being drawn started.
    pub(super) fn box_start(&self) -> Option<Pos2> {
        self.box_start
    }

    /// Starts (Some) or drops (None) a box zoom.
    pub(super) fn set_box_start(&mut self, at: Option<Pos2>) {
        self.box_start = at;
    }
}
