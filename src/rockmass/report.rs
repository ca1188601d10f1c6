//! The account of one cut rock mass: what `dda3d cut` prints and `summary.json` reports.

use serde::Serialize;

use crate::text::short;

/// What cutting one rock mass gave, for `dda3d cut`, the run's log and `summary.json` (whose
/// field names are those of the `serde` renames).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RockMassReport {
    pub name: String,
    pub blocks: usize,
    pub fixed: usize,
    /// The joint planes that cut the domain.
    pub planes: usize,
    /// The regions' volume and the blocks', m³.
    pub domain_volume: f64,
    pub volume: f64,
    /// The smallest block, m³.
    #[serde(rename = "smallest_block")]
    pub smallest: f64,
    /// Blocks dropped below `min_volume`, and their volume.
    #[serde(rename = "dropped_slivers")]
    pub dropped: usize,
    pub dropped_volume: f64,
    /// Cuts not made because a piece would have been a sliver (`max_aspect`).
    #[serde(rename = "cuts_not_made")]
    pub rejected_cuts: usize,
}

impl std::fmt::Display for RockMassReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "rock mass '{}': {} blocks ({} fixed) from {} joint planes; volume {} m³ of the \
             domain's {} m³ (relative difference {:.1e}); smallest block {} m³; {} slivers \
             dropped ({} m³); {} cuts not made (slivers)",
            self.name,
            self.blocks,
            self.fixed,
            self.planes,
            short(self.volume),
            short(self.domain_volume),
            (self.volume + self.dropped_volume - self.domain_volume).abs() / self.domain_volume,
            short(self.smallest),
            self.dropped,
            short(self.dropped_volume),
            self.rejected_cuts
        )
    }
}
