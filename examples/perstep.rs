//! Prints per-step solver statistics of a scene (diagnostics while tuning).
fn main() {
    let path = std::env::args().nth(1).expect("scene");
    let dur: f64 = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(0.5);
    let s = dda3d::scene::load(std::path::Path::new(&path)).unwrap();
    let mut solver = dda3d::solver::Solver::new(s.model, s.params);
    while solver.time < dur {
        let st = solver.step().unwrap().clone();
        println!(
            "t={:.4} dt={:.2e} oc={} alm={} fact={} cuts={} lock={} slide={} open={} pen={:.2e}",
            solver.time,
            st.time_step,
            st.open_close_iterations,
            st.alm_iterations,
            st.factorizations,
            st.time_step_cuts,
            st.contacts_lock,
            st.contacts_slide,
            st.contacts_open,
            st.max_penetration
        );
    }
}
