//! The window's end of the simulation: one thread, or two in lock-step for `--compare`, with
//! buffers for the step records they hand over to the panels.

use std::sync::Arc;

use winit::event_loop::EventLoopProxy;

use super::Wake;
use crate::viewer::compare_ui::{CompareUi, EditTarget};
use crate::viewer::sim::pair::{Side, SimPair};
use crate::viewer::sim::{Command, Frame, SimHandle, StepRecord};
use crate::viewer::state::UiState;
use crate::viewer::{ViewerError, ViewerOptions};

pub(super) enum SimLink {
    One {
        handle: SimHandle,
        records: Vec<StepRecord>,
    },
    Pair {
        pair: Box<SimPair>,
        records_a: Vec<StepRecord>,
        records_b: Vec<StepRecord>,
    },
}

impl SimLink {
    /// Starts the simulation of the options' scene (and of run B with `--compare`); each new
    /// frame wakes the event loop.
    pub fn start(
        opts: &ViewerOptions,
        proxy: EventLoopProxy<Wake>,
    ) -> Result<SimLink, ViewerError> {
        let scene = &opts.scene;
        let waker = move || {
            let _ = proxy.send_event(Wake);
        };
        let failed = |e: std::io::Error| {
            ViewerError::Failed(format!("cannot start the simulation thread: {e}"))
        };
        Ok(match &opts.compare {
            None => SimLink::One {
                handle: SimHandle::spawn(
                    scene.model.clone(),
                    scene.params.clone(),
                    opts.origin.clone(),
                    opts.speed,
                    opts.play,
                    Box::new(waker),
                )
                .map_err(failed)?,
                records: Vec::new(),
            },
            Some(b) => SimLink::Pair {
                pair: Box::new(
                    SimPair::spawn(
                        scene.model.clone(),
                        (scene.params.clone(), b.clone()),
                        opts.origin.clone(),
                        opts.speed,
                        opts.play,
                        waker,
                    )
                    .map_err(failed)?,
                ),
                records_a: Vec::new(),
                records_b: Vec::new(),
            },
        })
    }

    /// A's newest frame (the only run's, without a comparison).
    pub fn first_frame(&self) -> Option<Arc<Frame>> {
        match self {
            SimLink::One { handle, .. } => handle.latest(),
            SimLink::Pair { pair, .. } => pair.a.latest(),
        }
    }

    /// B's compare state for the panels, with a comparison.
    pub fn compare_ui(&self, opts: &ViewerOptions) -> Option<Box<CompareUi>> {
        let b = opts.compare.as_ref()?;
        let mut c = CompareUi::new(&opts.scene.params, b);
        c.ghost = opts.ghost;
        Some(Box::new(c))
    }

    /// Gives the panels the newest frame(s) and the step records since the last call.
    pub fn update(&mut self, ui: &mut UiState) {
        match self {
            SimLink::One { handle, records } => {
                let frame = handle.latest();
                handle.drain_records(records);
                ui.update(frame, records);
            }
            SimLink::Pair {
                pair,
                records_a,
                records_b,
            } => {
                let (a, b) = pair.tick();
                pair.drain_records(records_a, records_b);
                ui.update(Some(a), records_a);
                ui.update_b(b, records_b);
            }
        }
    }

    /// Sends a command of the toolbar or the keyboard.
    pub fn command(&mut self, cmd: Command, ui: &mut UiState) {
        match self {
            SimLink::One { handle, .. } => {
                let shown = matches!(cmd, Command::SetSpeed(_));
                let id = handle.send(cmd);
                if shown {
                    ui.params_sent(id);
                }
            }
            SimLink::Pair { pair, .. } => match cmd {
                // One checkpoint file per time: the two runs' states would overwrite each
                // other, and a state loaded into both would make B a copy of A.
                Command::SaveState(_) | Command::LoadState(_) => {
                    ui.error("Save and load state are not available in a comparison");
                }
                other => pair.command(other),
            },
        }
    }

    /// Sends the solver panel's edit, if any: to the one run, or to A, B or both.
    pub fn send_params(&mut self, ui: &mut UiState) {
        let Some((old, new)) = ui.param_edit() else {
            return;
        };
        match self {
            SimLink::One { handle, .. } => {
                let id = handle.send(Command::SetParams(Box::new(new)));
                ui.params_sent(id);
            }
            SimLink::Pair { pair, .. } => {
                let target = ui.compare.as_ref().map_or(EditTarget::A, |c| c.target);
                if matches!(target, EditTarget::A | EditTarget::Both) {
                    let id = pair
                        .side(Side::A)
                        .send(Command::SetParams(Box::new(new.clone())));
                    ui.params_sent(id);
                }
                let b = match target {
                    EditTarget::A => return,
                    EditTarget::B => new,
                    // B keeps the settings that set it apart; only the keys edited change.
                    EditTarget::Both => {
                        let now = ui
                            .compare
                            .as_ref()
                            .and_then(|c| c.frame_b.as_ref())
                            .map_or_else(|| new.clone(), |f| f.params.clone());
                        UiState::apply_edit_to(&old, &new, &now)
                    }
                };
                let id = pair.side(Side::B).send(Command::SetParams(Box::new(b)));
                if let Some(c) = ui.compare.as_mut() {
                    c.b_sent = id;
                }
            }
        }
    }

    /// B's frame of the pair shown, with a comparison (for the exit report).
    pub fn frame_b(ui: &UiState) -> Option<Arc<Frame>> {
        ui.compare.as_ref().and_then(|c| c.frame_b.clone())
    }
}
