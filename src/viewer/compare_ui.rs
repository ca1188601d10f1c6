//! What the viewer remembers of run B in a comparison (`view --compare`): B's newest frame (at
//! the same t as A's, see [`super::sim::pair`]), its plot history and 3-D scene, which run the
//! solver panel edits, the captions, and the difference of A and B over time.
//!
//! Run A stays where the plain viewer keeps its run ([`UiState::frame`], `history`, `scene`),
//! so every panel works unchanged on A; the compare panels read B from here.

use std::sync::Arc;

use super::sim::{Frame, StepRecord};
use super::state::{History, UiState};
use crate::compare::{caption, compare_snapshots, labels};
use crate::params::SolverParams;
use crate::params::table;
use crate::render::{RenderScene, SceneStyle};

/// Which run the solver panel's edits go to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EditTarget {
    A,
    B,
    Both,
}

/// Run B, and what ties it to A, as the panels show them.
pub struct CompareUi {
    pub frame_b: Option<Arc<Frame>>,
    pub history_b: History,
    pub scene_b: Option<RenderScene>,
    pub scene_b_version: u64,
    /// What `scene_b` was built from: (frame seq, style, wireframe).
    scene_b_key: Option<(u64, SceneStyle, bool)>,
    pub target: EditTarget,
    /// Id of the last SetParams sent to B (frames of B before it are stale for the widgets).
    pub b_sent: u64,
    /// The settings that differ, `name=value`, of A and of B.
    pub labels: (Vec<String>, Vec<String>),
    /// (t, largest block displacement difference between A and B in m, difference of their
    /// total contact force in N), one point per common time the window was shown.
    pub difference: Vec<[f64; 3]>,
    /// The 3-D view's texture of B (the app's second view target) and its rectangle in points.
    pub texture_b: Option<egui::TextureId>,
    pub view_rect_b: egui::Rect,
    /// One pane: A, with B drawn over it as a translucent ghost (instead of two panes).
    pub ghost: bool,
}

/// Common times kept for the difference plot (as the step history, a long run keeps its recent
/// past).
const DIFFERENCE_CAP: usize = 200_000;

impl CompareUi {
    pub fn new(a: &SolverParams, b: &SolverParams) -> CompareUi {
        CompareUi {
            frame_b: None,
            history_b: History::default(),
            scene_b: None,
            scene_b_version: 0,
            scene_b_key: None,
            target: EditTarget::A,
            b_sent: 0,
            labels: labels(a, b),
            difference: Vec::new(),
            texture_b: None,
            view_rect_b: egui::Rect::NOTHING,
            ghost: false,
        }
    }
}

impl UiState {
    /// Takes in B's frame of the shown pair (A's went through [`UiState::update`] first) and
    /// B's step records; adds a point to the difference plot when the pair moved on.
    pub fn update_b(&mut self, fb: Arc<Frame>, records: &mut Vec<StepRecord>) {
        let Some(fa) = self.frame.clone() else {
            return;
        };
        let Some(c) = self.compare.as_deref_mut() else {
            return;
        };
        if fb.generation != c.history_b.generation {
            c.history_b.generation = fb.generation;
            c.history_b.records.clear();
        }
        if fa.generation == fb.generation
            && fa.snapshot.time.to_bits() == fb.snapshot.time.to_bits()
        {
            let t = fa.snapshot.time;
            if c.difference.last().is_some_and(|p| p[0] > t) {
                c.difference.clear(); // a reset: the plot starts over
            }
            if c.difference.last().is_none_or(|p| p[0] < t) {
                let d = compare_snapshots(&fa.snapshot, &fb.snapshot);
                c.difference
                    .push([t, d.max_displacement_difference, d.contact_force_difference]);
                if c.difference.len() > DIFFERENCE_CAP {
                    c.difference.drain(..c.difference.len() - DIFFERENCE_CAP);
                }
            }
        }
        c.labels = labels(&fa.params, &fb.params);
        let generation = c.history_b.generation;
        c.history_b
            .records
            .extend(records.drain(..).filter(|r| r.generation == generation));
        let follow = c.target == EditTarget::B && fb.applied >= c.b_sent;
        c.frame_b = Some(fb.clone());
        if follow {
            self.follow_edit(&fb.params);
        }
    }

    /// Sets which run the solver panel edits; the widgets show that run's settings at once.
    pub fn set_edit_target(&mut self, target: EditTarget) {
        let Some(c) = self.compare.as_deref_mut() else {
            return;
        };
        c.target = target;
        let shown = match target {
            EditTarget::B => c.frame_b.clone(),
            EditTarget::A | EditTarget::Both => self.frame.clone(),
        };
        if let Some(f) = shown {
            self.follow_edit(&f.params);
        }
    }

    /// Whether the widgets follow A's frames (not while they edit B alone).
    pub(super) fn edit_follows_a(&self) -> bool {
        self.compare
            .as_deref()
            .is_none_or(|c| c.target != EditTarget::B)
    }

    /// Builds B's scene (the style of A's, so colours and arrow lengths compare), captioned
    /// with its side; and captions A's.
    pub(super) fn build_scene_b(&mut self) {
        let style = self.style();
        let wireframe = self.display.wireframe;
        let Some(c) = self.compare.as_deref_mut() else {
            return;
        };
        let (Some(fa), Some(fb)) = (self.frame.clone(), c.frame_b.clone()) else {
            return;
        };
        if let Some(s) = self.scene.as_mut() {
            s.caption.scene_name = caption("A", &fa.params, &c.labels.0);
            if c.ghost {
                // One pane: the caption says what the blue ghost is.
                let b = caption("B", &fb.params, &c.labels.1);
                s.caption.scene_name = format!("{} | ghost {b}", s.caption.scene_name);
            }
        }
        let key = (fb.seq, style.clone(), wireframe);
        if c.scene_b.is_some() && c.scene_b_key.as_ref() == Some(&key) {
            if let Some(s) = c.scene_b.as_mut() {
                s.caption.scene_name = caption("B", &fb.params, &c.labels.1);
            }
            return;
        }
        match RenderScene::build(&fb.snapshot, &style, &self.scene_frame) {
            Ok(mut scene) => {
                if wireframe {
                    scene.solids.clear();
                }
                scene.caption.scene_name = caption("B", &fb.params, &c.labels.1);
                c.scene_b = Some(scene);
                c.scene_b_version += 1;
                c.scene_b_key = Some(key);
            }
            Err(e) => {
                c.scene_b = None;
                self.error(format!("cannot draw this step of B: {e}"));
            }
        }
    }

    /// The edited parameters for a change to both runs: `b` (B's settings now) with every key
    /// that the edit changed set to its new value, so that B keeps what sets it apart.
    pub fn apply_edit_to(old: &SolverParams, new: &SolverParams, b: &SolverParams) -> SolverParams {
        let mut out = b.clone();
        for p in table::ALL.iter().filter(|p| (p.get)(old) != (p.get)(new)) {
            // The text of a valid value reads back as that value.
            let _ = (p.set)(&mut out, &p.text(new));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Method;

    /// The rockfall's UiState with a comparison, and a frame of each side at t = 0 (B with the
    /// penalty method).
    fn rockfall() -> (UiState, Frame, Frame) {
        let (mut state, a) = crate::viewer::state::tests::rockfall_state(0);
        let mut b = a.clone();
        b.params.method = Method::Penalty;
        state.compare = Some(Box::new(CompareUi::new(&a.params, &b.params)));
        (state, a, b)
    }

    #[test]
    fn an_edit_to_both_changes_the_keys_edited_and_keeps_what_sets_b_apart() {
        let (_, a, b) = rockfall();
        let mut new = a.params.clone();
        new.contact.alpha = 7.5;
        new.joint.friction_angle = 20.0;
        let to_b = UiState::apply_edit_to(&a.params, &new, &b.params);
        assert_eq!(to_b.method, Method::Penalty, "B stays penalty");
        assert_eq!(to_b.contact.alpha, 7.5);
        assert_eq!(to_b.joint.friction_angle, 20.0);
        let mut back = to_b.clone();
        back.method = Method::Alm;
        assert_eq!(back, new, "nothing else differs");
    }

    #[test]
    fn the_widgets_follow_the_side_edited_and_the_difference_plot_the_common_times() {
        let (mut st, a, b) = rockfall();
        st.update(Some(Arc::new(a.clone())), &mut Vec::new());
        st.update_b(Arc::new(b.clone()), &mut Vec::new());
        assert_eq!(st.params.edit.method, Method::Alm, "A by default");
        let c = st.compare.as_ref().unwrap();
        assert_eq!(c.labels.0, vec!["method=alm".to_owned()]);
        assert_eq!(c.labels.1, vec!["method=penalty".to_owned()]);
        assert_eq!(
            c.difference,
            vec![[0.0, 0.0, 0.0]],
            "one common time, no difference yet"
        );
        st.set_edit_target(EditTarget::B);
        assert_eq!(
            st.params.edit.method,
            Method::Penalty,
            "B's settings at once"
        );
        // A's next frame leaves the widgets on B.
        st.update(Some(Arc::new(Frame { seq: 2, ..a })), &mut Vec::new());
        assert_eq!(st.params.edit.method, Method::Penalty);
        assert!(st.param_change().is_none(), "nothing to send");
        st.set_edit_target(EditTarget::Both);
        assert_eq!(
            st.params.edit.method,
            Method::Alm,
            "both: A's settings shown"
        );
        // A pair at two different times adds no point.
        let later = Frame {
            seq: 2,
            snapshot: Arc::new(crate::snapshot::Snapshot {
                time: 0.01,
                ..(*b.snapshot).clone()
            }),
            ..b
        };
        st.update_b(Arc::new(later), &mut Vec::new());
        assert_eq!(st.compare.as_ref().unwrap().difference.len(), 1);
    }
}
