//! What a contact carries from one step to the next (reference §4.5): its state, its multiplier
//! and adapted penalty, the reference point of its shear spring, its sliding direction, and what
//! is left of its cohesion. The solver keeps one record per [`super::ContactKey`].

use super::{ContactKey, ContactState};
use crate::physics::geometry::Vec3;

/// The records the solver keeps, by contact. Looked up several times per contact per step, so
/// hashed with rustc's Fx hash, not SipHash; nothing depends on the map's order (a checkpoint
/// sorts the records by key).
pub type RecordMap = rustc_hash::FxHashMap<ContactKey, ContactRecord>;

/// The history of one contact.
#[derive(Clone, Copy, Debug)]
pub struct ContactRecord {
    pub state: ContactState,
    /// λ, N (ALM only).
    pub lambda: f64,
    /// p_n, N/m.
    pub penalty: f64,
    /// Last normal force λ + p_n d_n (ALM) or p_n d_n (penalty), N.
    pub normal_force: f64,
    pub shear_force: f64,
    pub penetration: f64,
    /// Reference point P_b of a locked contact, moved with block j.
    pub reference: Vec3,
    /// Sliding direction of a relative to b.
    pub tau: Vec3,
    pub normal: Vec3,
    /// Closed since the start and never opened or slid: still has cohesion.
    pub intact: bool,
    /// Joint area attributed to the contact for cohesion, m².
    pub cohesion_area: f64,
    /// Overlap the contact was first seen with, m, taken out of d0 so that the contact stops
    /// further penetration without pushing the blocks apart (see the solver's `activate`).
    pub overlap: f64,
}
