//! The Z-plane view's own state: the zoom, the drag in progress and the table's selection. The
//! controls (`zplane`), the plot (`plot`) and the cluster table (`cluster_table`) all read it; none
//! of them imports another.
use std::collections::BTreeMap;

use egui_plot::{PlotBounds, PlotTransform};
use num_complex::Complex64;

use crate::core::identification::cluster::Cluster;
use crate::ui::derived::LiveView;

/// Which part of a cluster circle is dragged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handle {
    Centre,
    Rim,
}

/// A cluster drag in progress: the live path runs on [`ClusterDrag::preview`] every frame.
#[derive(Clone, Debug)]
pub struct ClusterDrag {
    pub output: String,
    pub index: usize,
    pub handle: Handle,
    /// The clusters when the drag started.
    pub base: Vec<Cluster>,
    /// The dragged cluster as it is now.
    pub current: Cluster,
    /// Centre minus the pointer where the drag started (so the centre does not jump).
    pub grab_offset: [f64; 2],
}

impl ClusterDrag {
    /// The clusters with the dragged one where it is now.
    pub fn preview(&self) -> Vec<Cluster> {
        let mut clusters = self.base.clone();
        if let Some(slot) = clusters.get_mut(self.index) {
            *slot = self.current.clone();
        }
        clusters
    }
}

/// The detail plot's view: a centre and the half-width of the x range (the plot keeps the aspect).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZoomView {
    pub centre: [f64; 2],
    pub half_width: f64,
}

impl ZoomView {
    pub const WHOLE: Self = Self { centre: [0.0, 0.0], half_width: 1.15 };

    /// Around the clusters (their upper half-plane side), the points `extra` (the reduced model's
    /// roots) and z = 1; the whole circle if there are no clusters.
    pub fn fit(clusters: &[Cluster], extra: &[Complex64]) -> Self {
        if clusters.is_empty() {
            return Self::WHOLE;
        }
        // z = 1 and room right of the circle for the angle labels.
        let (mut lo, mut hi) = ([1.0f64, -0.05f64], [1.08f64, 0.05f64]);
        let circles = clusters.iter().map(|c| (c.centre, c.radius));
        let points = extra.iter().filter(|z| z.im >= 0.0 && z.norm() < 1.5).map(|z| (*z, 0.02));
        for (centre, radius) in circles.chain(points) {
            lo = [lo[0].min(centre.re - radius), lo[1].min(centre.im - radius)];
            hi = [hi[0].max(centre.re + radius), hi[1].max(centre.im + radius)];
        }
        let half_width = (0.5 * (hi[0] - lo[0]).max(hi[1] - lo[1]) * 1.35).clamp(0.05, 1.15);
        Self { centre: [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])], half_width }
    }

    pub fn bounds(&self) -> PlotBounds {
        let [x, y] = self.centre;
        let h = self.half_width;
        PlotBounds::from_min_max([x - h, y - h], [x + h, y + h])
    }

    /// Zoom by `factor` (< 1 zooms in) keeping the point `at` where it is.
    pub fn zoom_about(&mut self, at: [f64; 2], factor: f64) {
        let factor = factor.clamp(0.5, 2.0);
        let half_width = (self.half_width * factor).clamp(1e-3, 3.0);
        let f = half_width / self.half_width;
        self.centre = [at[0] + (self.centre[0] - at[0]) * f, at[1] + (self.centre[1] - at[1]) * f];
        self.half_width = half_width;
    }
}

#[derive(Default)]
pub struct ZPlaneViewState {
    /// The selected cluster (index into the output's clusters).
    pub selected: Option<usize>,
    pub drag: Option<ClusterDrag>,
    pub panning: bool,
    /// The detail view of each output.
    pub zoom: BTreeMap<String, ZoomView>,
    /// Plot coordinates ↔ screen of the last frame (tests use it to find a cluster's handles).
    pub last_transform: Option<PlotTransform>,
}

/// The view that fits the clusters and the reduced model's roots.
pub fn fit_view(view: &LiveView<'_>) -> ZoomView {
    let roots = match view.live {
        Ok(live) => {
            let tf = &live.model.wiener.linear.tf;
            let mut roots = tf.poles().unwrap_or_default();
            roots.extend(tf.zeros().unwrap_or_default());
            roots
        }
        Err(_) => Vec::new(),
    };
    ZoomView::fit(view.clusters, &roots)
}

impl ZPlaneViewState {
    /// The clusters being dragged, for the live preview.
    pub fn preview_request(&self) -> Option<(String, Vec<Cluster>)> {
        self.drag.as_ref().map(|d| (d.output.clone(), d.preview()))
    }
}
