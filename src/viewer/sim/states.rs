//! Save state / Load state: the viewer's run written to and read from the checkpoint files of
//! `dda3d run --checkpoint-every` (`crate::solver::checkpoint`), so a state saved in the viewer
//! resumes with `run --resume`, and a checkpoint of a headless run opens in the viewer.

use std::path::{Path, PathBuf};

use crate::model::Model;
use crate::solver::Solver;
use crate::solver::checkpoint::{self, EXTENSION};

/// Writes the solver's state to `dir/checkpoint_<t>.ckpt`. Returns the message for the window.
pub fn save(solver: &Solver, dir: &Path) -> Result<String, String> {
    let path = dir.join(checkpoint::file_name(solver.time));
    crate::files::create_dir_clearly(dir).map_err(|e| {
        format!(
            "{}: cannot save the state: cannot create its directory: {e}",
            dir.display()
        )
    })?;
    checkpoint::save(solver, &path)
        .map_err(|e| format!("{}: cannot save the state: {e}", path.display()))?;
    Ok(format!("state saved to {}", path.display()))
}

/// Reads the checkpoint at `path` for the viewer's scene `model`: one of another scene (other
/// blocks) is refused, since the window's meshes, selection and reset belong to this one.
pub fn load(path: &Path, model: &Model) -> Result<Solver, String> {
    let solver = checkpoint::load(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let same = solver.model.blocks.len() == model.blocks.len()
        && solver
            .model
            .blocks
            .iter()
            .zip(&model.blocks)
            .all(|(a, b)| a.name == b.name && a.topo.faces == b.topo.faces);
    if !same {
        return Err(format!(
            "{}: a state of '{}' ({} blocks), not of this scene '{}' ({} blocks)",
            path.display(),
            solver.model.name,
            solver.model.blocks.len(),
            model.name,
            model.blocks.len()
        ));
    }
    Ok(solver)
}

/// The checkpoint files in `dir`, latest simulated time first (their names sort by time only
/// within a width, so the time is read back from the name).
pub fn list(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut found: Vec<(f64, PathBuf)> = entries
        .filter_map(|e| {
            let path = e.ok()?.path();
            let name = path.file_name()?.to_str()?;
            let t = name
                .strip_prefix("checkpoint_")?
                .strip_suffix(&format!(".{EXTENSION}"))?
                .parse::<f64>()
                .ok()?;
            Some((t, path))
        })
        .collect();
    found.sort_by(|a, b| b.0.total_cmp(&a.0).then_with(|| a.1.cmp(&b.1)));
    found.into_iter().map(|(_, p)| p).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::sim::test_support::rockfall;

    #[test]
    fn a_saved_state_lists_first_and_loads_back_to_the_same_next_step() {
        let scene = rockfall();
        let dir = std::env::temp_dir().join(format!("dda3d-states-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut solver = Solver::new(scene.model.clone(), scene.params.clone());
        solver.step().unwrap();
        save(&solver, &dir).unwrap();
        for _ in 0..3 {
            solver.step().unwrap();
        }
        let message = save(&solver, &dir).unwrap();
        let files = list(&dir);
        assert_eq!(files.len(), 2);
        assert!(
            message.contains(&*files[0].to_string_lossy()),
            "latest first"
        );
        let mut loaded = load(&files[0], &scene.model).unwrap();
        loaded.step().unwrap();
        solver.step().unwrap();
        let (a, b) = (loaded.snapshot(), solver.snapshot());
        assert_eq!(a.time.to_bits(), b.time.to_bits());
        for (x, y) in a.blocks.iter().zip(&b.blocks) {
            assert_eq!(x.centroid.map(f64::to_bits), y.centroid.map(f64::to_bits));
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_state_of_another_scene_is_refused() {
        let scene = rockfall();
        let dir = std::env::temp_dir().join(format!("dda3d-states-other-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let solver = Solver::new(scene.model.clone(), scene.params.clone());
        save(&solver, &dir).unwrap();
        let mut other = scene.model.clone();
        other.blocks.pop();
        let e = load(&list(&dir)[0], &other).err().expect("refused");
        assert!(e.contains("not of this scene"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
