//! The reusable model workspace (`model::Data`): the same FK and Jacobian as the allocating
//! wrappers, analytic columns against central finite differences, and **no heap allocation** per
//! pose on a warm workspace (FK, tilted FK, Jacobian, and the per-pose accumulation of one LM
//! iteration), counted by a global allocator in this test binary.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use nalgebra::DVector;
use rigctl::calib::accumulate::PositionNormalProblem;
use rigctl::calib::default_selection;
use rigctl::calib::lm::LmConfig;
use rigctl::calib::measured::PosePoints;
use rigctl::calib::normal::{solve_normal, Normal, NormalProblem};
use rigctl::model::{katana450, ur5, Data, Model, Tilt, Wrt};

use crate::common::record::record;

/// Workspace against the allocating wrappers (mm, mm per unit).
const WRAPPER_TOL: f64 = 1e-12;
/// Analytic columns against central differences, relative.
const FD_REL_TOL: f64 = 1e-6;

struct Counting;

thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by this thread while running `f`.
fn allocations(f: impl FnOnce()) -> usize {
    let before = ALLOCS.with(Cell::get);
    f();
    ALLOCS.with(Cell::get) - before
}

/// A Katana with every kind of parameter away from zero (harmonics, payload, twists, base).
fn busy_katana() -> Model {
    let mut m = katana450(200.0).unwrap();
    for (n, v) in [
        ("dth2", 0.3),
        ("al3", 0.2),
        ("be4", -0.1),
        ("enc_j2_h1_sin", 0.05),
        ("enc_j3_h2_cos", -0.04),
        ("payload_kg", 0.5),
        ("base_rx", 0.02),
        ("scale_ppm", 30.0),
        ("tool_dx", 1.5),
    ] {
        m.set_param(n, v).unwrap();
    }
    m
}

fn poses(model: &Model, n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|k| {
            let t = k as f64;
            model
                .joint_limits()
                .iter()
                .enumerate()
                .map(|(j, l)| {
                    let u = 0.5 + 0.45 * (1.7 * t + 2.3 * j as f64).sin();
                    l[0] + u * (l[1] - l[0])
                })
                .collect()
        })
        .collect()
}

#[test]
fn workspace_matches_wrappers_and_finite_differences() {
    let model = busy_katana();
    let all: Vec<Wrt> = (0..model.params().len())
        .map(Wrt::Param)
        .chain((0..model.n_joints()).map(Wrt::Joint))
        .collect();
    let mut d = Data::new(&model);
    for q in poses(&model, 6) {
        for tilt in [Tilt::Off, Tilt::Static] {
            model.jacobian_with(&mut d, &q, tilt, &all).unwrap();
            let (fk, jac) = model.position_jacobian(&q, tilt, &all).unwrap();
            assert!((d.position_mm() - fk.position_mm).norm() < WRAPPER_TOL);
            for (k, w) in all.iter().enumerate() {
                assert!(
                    (d.jacobian()[k] - jac.column(k)).norm() < WRAPPER_TOL,
                    "{w:?}"
                );
                // Central differences of the workspace FK.
                let h = 1e-6;
                let eval = |delta: f64| {
                    let mut m = model.clone();
                    let mut qq = q.clone();
                    match *w {
                        Wrt::Param(i) => {
                            let v = m.params()[i].value;
                            m.set_param_at(i, v + delta).unwrap();
                        }
                        Wrt::Joint(j) => qq[j] += delta,
                        Wrt::Lateral(j) => {
                            let c = m.lateral_compliance_at(j);
                            m.set_lateral_compliance(j, c + delta).unwrap();
                        }
                    }
                    let mut dd = Data::new(&m);
                    m.fk_with(&mut dd, &qq, tilt).unwrap();
                    dd.position_mm()
                };
                let fd = (eval(h) - eval(-h)) / (2.0 * h);
                let an = d.jacobian()[k];
                let tol = FD_REL_TOL * an.norm().max(1.0);
                assert!(
                    (fd - an).norm() <= tol,
                    "{w:?} {tilt:?}: fd {fd:?} vs {an:?}"
                );
            }
        }
    }
    record("wrapper_tolerance", WRAPPER_TOL);
    record("fd_tolerance", FD_REL_TOL);
}

#[test]
fn warm_workspace_does_not_allocate() {
    let model = busy_katana();
    let qs = poses(&model, 50);
    let geometric: Vec<Wrt> = default_selection(&model, true)
        .into_iter()
        .map(Wrt::Param)
        .collect();
    let mut d = Data::new(&model);
    // Warm up (the Jacobian column buffer grows once).
    model
        .jacobian_with(&mut d, &qs[0], Tilt::Static, &geometric)
        .unwrap();
    let n = allocations(|| {
        for q in &qs {
            model.fk_with(&mut d, q, Tilt::Off).unwrap();
            model.fk_with(&mut d, q, Tilt::Static).unwrap();
            model
                .jacobian_with(&mut d, q, Tilt::Off, &geometric)
                .unwrap();
            model
                .jacobian_with(&mut d, q, Tilt::Static, &geometric)
                .unwrap();
        }
    });
    assert_eq!(
        n, 0,
        "FK / tilted FK / Jacobian allocated {n} times for 50 poses"
    );
    record("katana_warm_allocations", n);

    // A parameter change refreshes the cache in place.
    let mut moved = model.clone();
    moved.set_param("al2", 90.1).unwrap();
    let n = allocations(|| moved.fk_with(&mut d, &qs[1], Tilt::Static).unwrap());
    assert_eq!(n, 0);

    // UR5 (no tilting data).
    let ur = ur5().unwrap();
    let mut du = Data::new(&ur);
    let q6 = [10.0, -80.0, 70.0, -30.0, 60.0, 15.0];
    let wrt: Vec<Wrt> = (0..ur.params().len()).map(Wrt::Param).collect();
    ur.jacobian_with(&mut du, &q6, Tilt::Off, &wrt).unwrap();
    let n = allocations(|| ur.jacobian_with(&mut du, &q6, Tilt::Off, &wrt).unwrap());
    assert_eq!(n, 0);
    record("ur5_warm_allocations", n);
}

fn measured(model: &Model, n: usize) -> PosePoints {
    let mut truth = model.clone();
    truth.set_param("dth3", 0.05).unwrap();
    let q_deg = poses(model, n);
    let xyz_mm = q_deg
        .iter()
        .map(|q| truth.position_mm(q, Tilt::Static).unwrap())
        .collect();
    PosePoints { q_deg, xyz_mm }
}

/// One LM iteration's per-pose work (normal equations + a trial residual sum) allocates nothing
/// per pose: on one chunk (one thread) only the matrix product's packing buffer; over several
/// chunks at most one more per chunk of `CHUNK_POSES` poses and the second thread's fixed cost;
/// and a whole solve allocates about the same (small, n x n algebra and the helper thread)
/// whatever the pose count.
#[test]
fn lm_iteration_allocations_do_not_grow_with_the_poses() {
    let model = busy_katana();
    let sel = default_selection(&model, false);
    let mut per_solve = Vec::new();
    let mut per_iteration = Vec::new();
    for n in [200, 1000, 4000] {
        let poses = measured(&model, n);
        let mut p = PositionNormalProblem::new(&model, &poses, sel.clone(), true);
        let x: DVector<f64> =
            DVector::from_iterator(sel.len(), sel.iter().map(|&c| model.params()[c].value));
        let mut eq = Normal::zeros(sel.len());
        p.normal(&x, &mut eq).unwrap();
        let count = allocations(|| {
            p.normal(&x, &mut eq).unwrap();
            p.sum_sq(&x).unwrap();
        });
        per_iteration.push(count);
        let mut p = PositionNormalProblem::new(&model, &poses, sel.clone(), true);
        let lm = LmConfig {
            max_iterations: 1,
            max_iterations_hard: 1,
            ..LmConfig::default()
        };
        p.normal(&x, &mut eq).unwrap();
        per_solve.push(allocations(|| {
            solve_normal(&mut p, x.clone(), &lm).unwrap();
        }));
    }
    // 200 poses are one chunk (no thread); 1000 and 4000 poses several chunks on two threads
    const {
        assert!(
            200 <= rigctl::calib::accumulate::CHUNK_POSES
                && 1000 > rigctl::calib::accumulate::CHUNK_POSES
        )
    };
    let chunks = |n: usize| n.div_ceil(rigctl::calib::accumulate::CHUNK_POSES);
    assert!(per_iteration[0] <= 1, "one chunk: {per_iteration:?}");
    assert!(
        per_iteration[2] <= per_iteration[1] + chunks(4000) - chunks(1000),
        "{per_iteration:?}"
    );
    assert!(per_iteration[1] < 50, "{per_iteration:?}");
    assert!(
        per_solve[2] <= per_solve[1] + 4 * (chunks(4000) - chunks(1000)),
        "{per_solve:?}"
    );
    assert!(per_solve[0] < 200 && per_solve[1] < 400, "{per_solve:?}");
    // the counts beyond one chunk depend on the threads of the machine
    record("iteration_allocations", per_iteration);
    record("solve_allocations", per_solve);
}
