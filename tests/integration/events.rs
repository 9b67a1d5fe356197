//! Bubble events: coalescence (summed gas at the content-weighted centre) and a bubble
//! reaching a face (the run ends there, everything before is kept, the summary names it).

use decophantom::gas::GasMix;
use decophantom::phantom::grid::Face;
use decophantom::phantom::params::{BubblePlacement, PhantomParams};
use decophantom::phantom::sim::{Ending, Event, Recorder, Simulation};
use decophantom::profile::PressureHistory;
use decophantom::units::ATM_PA;

/// Saturated at 10 atm, then a fast decompression to 1 atm and a hold: strong growth.
fn decompression() -> PressureHistory {
    PressureHistory::with_gas(
        "decomp",
        vec![0.0, 10.0, 1800.0],
        vec![10.0 * ATM_PA, ATM_PA, ATM_PA],
        GasMix::AIR,
        0.0,
    )
    .unwrap()
}

fn base() -> PhantomParams {
    let mut p = PhantomParams::box_phantom([2.0e-3, 2.0e-3, 2.0e-3], 100e-6);
    p.min_radius = 10e-6;
    p.open_faces = vec![];
    p.numerics.record_interval = 0.0;
    p
}

#[test]
fn touching_bubbles_coalesce_with_summed_gas_at_the_content_weighted_centre() {
    let mut p = base();
    p.bubbles = BubblePlacement::Explicit(vec![
        ([0.8e-3, 1.0e-3, 1.0e-3], 60e-6),
        ([1.2e-3, 1.0e-3, 1.0e-3], 40e-6),
    ]);
    let prof = decompression();
    let mut sim = Simulation::new(&p, &prof).unwrap();
    let mut rec = Recorder::default();
    let s = sim.run(&prof, &mut rec).unwrap();
    let (time, into, absorbed) = s
        .events
        .iter()
        .find_map(|e| match e {
            Event::Coalesced {
                time,
                into,
                absorbed,
            } => Some((*time, *into, *absorbed)),
            _ => None,
        })
        .expect("the two bubbles must meet");
    // the frame just before the merge: both present; the first frame after: one, holding the sum
    let before = rec.frames.iter().rev().find(|f| f.time < time).unwrap();
    let after = rec.frames.iter().find(|f| f.time >= time).unwrap();
    assert_eq!(before.bubbles.len(), 2);
    assert_eq!(after.bubbles.len(), 1);
    assert_eq!(after.bubbles[0].id, into);
    let a = before.bubbles.iter().find(|b| b.id == into).unwrap();
    let b = before.bubbles.iter().find(|b| b.id == absorbed).unwrap();
    let (na, nb): (f64, f64) = (a.moles.iter().sum(), b.moles.iter().sum());
    // independent expectation: content-weighted centre of the two bubbles one frame earlier
    // (they exchange a little gas in that last step, so compare to 1 % of the separation)
    let x = (a.position[0] * na + b.position[0] * nb) / (na + nb);
    assert!(
        (after.bubbles[0].position[0] - x).abs() < 0.01 * 0.4e-3,
        "{} vs {x}",
        after.bubbles[0].position[0]
    );
    assert!(na >= nb, "the bubble with more gas survives");
    // gas is conserved through the merge (sealed phantom)
    assert!(s.gas_balance_error < 1e-9, "{}", s.gas_balance_error);
}

#[test]
fn a_bubble_reaching_a_face_ends_the_run_and_is_named() {
    let mut p = base();
    p.bubbles = BubblePlacement::Explicit(vec![([1.0e-3, 1.0e-3, 0.25e-3], 60e-6)]);
    let prof = decompression();
    let mut sim = Simulation::new(&p, &prof).unwrap();
    let mut rec = Recorder::default();
    let s = sim.run(&prof, &mut rec).unwrap();
    match s.ending {
        Ending::BubbleReachedFace { bubble, face, time } => {
            assert_eq!(bubble, 0);
            assert_eq!(face, Face::Bottom);
            assert!(time < prof.duration_s());
            assert_eq!(s.end_time, time);
            // everything up to it is kept: the last frame is at that time, and the bubble touches z = 0
            let last = rec.frames.last().unwrap();
            assert_eq!(last.time, time);
            assert!(last.bubbles[0].radius >= 0.25e-3);
            // the bubble was not moved
            assert_eq!(last.bubbles[0].position, [1.0e-3, 1.0e-3, 0.25e-3]);
        }
        other => panic!("expected the bubble to reach the bottom face, got {other:?}"),
    }
}

/// The solver checks its own gas balance: gas that appears from nowhere (here: the field edited
/// behind the solver's back, without `rebase_balance`) stops the run with a solver error.
#[test]
fn a_lost_gas_balance_stops_the_run() {
    let mut p = base();
    p.bubbles = BubblePlacement::Explicit(vec![([1.0e-3; 3], 60e-6)]);
    let prof = decompression();
    let mut sim = Simulation::new(&p, &prof).unwrap();
    sim.field_mut(0)[0] *= 2.0;
    match sim.run(&prof, &mut Recorder::default()) {
        Err(decophantom::error::Error::Solver(m)) => assert!(m.contains("gas balance"), "{m}"),
        other => panic!("expected a gas-balance error, got {other:?}"),
    }
}
