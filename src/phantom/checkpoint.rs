//! Checkpoints: the whole state of a run, saved after a complete step, so that a long
//! `simulate` survives being stopped (Ctrl-C, a killed job, a reboot) and continues later with
//! results byte-identical to an uninterrupted run (issue 11, "Long work survives interruption").
//!
//! # What is saved
//!
//! Everything the time loop ([`Simulation::run`]) carries from one step to the next: the time;
//! every gas field of the grid (all cells, inside and outside); every bubble ever created (id,
//! centre, R0, P0, content per gas, radius, fate); the bubbles' step-exchange state; the
//! open-face/perfusion inflow, the balance reference and the displaced-gas counter; the gel
//! each bubble displaces and the cells it holds out of the gel (the grid's codes and interior
//! spans follow from that set); which nucleus became which bubble; the loop's own state (the
//! previous step, the step the bubbles' error allows, the next record time, the peaks, the step
//! counts, the events, the per-bubble tensions and fluxes); and every frame recorded so far.
//! What is not saved is derived from the inputs when the run is rebuilt (grid mask, gas
//! properties, explicit limits, nuclei positions and thresholds — the nucleation models draw
//! their population once, at set-up, so no random generator runs during the time loop) or is
//! scratch space rewritten before it is read (diffusion scratch, kernel and sphere buffers).
//!
//! # Which inputs
//!
//! A checkpoint resumes only the run it came from: it holds a canonical text of the inputs as
//! parsed and validated — the phantom's every setting (its `name` left out: it only labels
//! outputs) and the pressure history (breakpoints, gases, water vapour; its label left out) —
//! and a 64-bit FNV-1a hash of each. File paths play no part. A resume with other inputs is
//! refused (exit 2) naming the checkpoint file and the first setting that differs.
//!
//! # File format (version [`FORMAT_VERSION`])
//!
//! Little-endian throughout; `u64` lengths before every sequence; `f64` as its IEEE-754 bits
//! (exact, NaN and infinities included); `usize` as `u64`; strings as UTF-8 bytes.
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `DCPHCKPT` |
//! | 4 | format version, `u32` |
//! | 8 | payload length *L*, `u64` |
//! | *L* | payload: crate version (string); inputs (per section: name, hash `u64`, canonical text — empty when over 1 MiB); the run state; the frames |
//! | 8 | FNV-1a 64 of every byte before it |
//!
//! The Fig. 5 grid (733 410 cells inside a box of 935 k, × 2 gases) makes a checkpoint of
//! 15.1 MB at mid-run (0.14–0.17 s to encode, write and flush). It is written to
//! a temporary file beside its place, flushed to disk and renamed over it, so a checkpoint file
//! is always whole. A file of another format version, of another decophantom version, truncated
//! or corrupt is refused with exit 2 (never a panic): every length is checked against the bytes
//! left before anything is allocated, and every index against the rebuilt grid and bubbles.

use super::bubble::{Bubble, BubbleFate};
use super::displacement::Displaced;
use super::fields::Fields;
use super::grid::Face;
use super::params::PhantomParams;
use super::sim::{
    BubbleFrame, Ending, Event, Frame, LoadingHistory, LoopState, Observer, RunLog, RunSummary,
    Simulation, StepExchange,
};
use crate::error::{Error, InputError};
use crate::gas::Gas;
use crate::profile::PressureHistory;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Version of the file format written; files of other versions are refused.
pub const FORMAT_VERSION: u32 = 4;
/// The first eight bytes of every checkpoint file.
pub const MAGIC: &[u8; 8] = b"DCPHCKPT";
/// Name of the checkpoint file in its folder.
pub const FILE_NAME: &str = "checkpoint.dcp";
/// Canonical texts longer than this are kept as their hash only.
const MAX_TEXT: usize = 1 << 20;

/// FNV-1a, 64 bit: a stable hash (the standard library's may change between Rust versions).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

// ---------------------------------------------------------------------------------------------
// inputs

/// One input of a run in canonical form.
#[derive(Debug, Clone, PartialEq)]
pub struct InputSection {
    /// What it is (`phantom`, `profile`).
    pub name: String,
    /// FNV-1a 64 of the canonical text.
    pub hash: u64,
    /// The canonical text (empty when it was longer than 1 MiB: the hash alone is kept).
    pub text: String,
}

impl InputSection {
    fn new(name: &str, text: String) -> Self {
        InputSection {
            name: name.into(),
            hash: fnv1a(text.as_bytes()),
            text: if text.len() <= MAX_TEXT {
                text
            } else {
                String::new()
            },
        }
    }
}

/// The identity of a run's inputs: what a checkpoint must match to be resumed.
#[derive(Debug, Clone, PartialEq)]
pub struct Inputs {
    /// The sections, in a fixed order.
    pub sections: Vec<InputSection>,
}

impl Inputs {
    /// The identity of a run of `profile` through `params` (both as parsed and validated).
    pub fn new(params: &PhantomParams, profile: &PressureHistory) -> Self {
        Inputs {
            sections: vec![
                InputSection::new("phantom", phantom_text(params)),
                InputSection::new("profile", profile_text(profile)),
            ],
        }
    }

    /// `None` when `self` (this run's) and `saved` (a checkpoint's) are the same inputs, else
    /// what differs, in words.
    pub fn difference(&self, saved: &Inputs) -> Option<String> {
        let names = |i: &Inputs| {
            i.sections
                .iter()
                .map(|s| s.name.clone())
                .collect::<Vec<_>>()
        };
        if names(self) != names(saved) {
            return Some(format!(
                "it describes the inputs as [{}], this run as [{}]",
                names(saved).join(", "),
                names(self).join(", ")
            ));
        }
        for (here, there) in self.sections.iter().zip(&saved.sections) {
            if here.hash == there.hash && here.text == there.text {
                continue;
            }
            let detail = if here.text.is_empty() || there.text.is_empty() {
                format!(
                    "content hash {:016x} here, {:016x} in the checkpoint",
                    here.hash, there.hash
                )
            } else {
                match first_difference(&here.text, &there.text) {
                    Some(d) => d,
                    None => format!(
                        "content hash {:016x} here, {:016x} in the checkpoint",
                        here.hash, there.hash
                    ),
                }
            };
            return Some(format!("the {} differs: {detail}", here.name));
        }
        None
    }
}

/// The phantom's settings as parsed and validated (`Debug`, one field a line; f64 printed
/// exactly), its name left out.
fn phantom_text(params: &PhantomParams) -> String {
    let mut p = params.clone();
    p.name = String::new();
    format!("{p:#?}")
}

/// The pressure history: water vapour, inert-only flag, the phantom's starting saturation
/// when it is not the first segment's gas at the first pressure (the rule of every history
/// before the saturation was stated, so their checkpoints still match), then one line per
/// breakpoint (time, absolute pressure, gas of the segment that starts there); its label left
/// out.
pub(crate) fn profile_text(profile: &PressureHistory) -> String {
    let mut s = format!(
        "vapour_pa: {:?}\ninert_only: {}\n",
        profile.vapour_pa, profile.inert_only
    );
    let sat = profile.saturation;
    if sat.gas != profile.gas[0] || sat.ambient_pa != profile.ambient_pa[0] {
        s.push_str(&format!(
            "saturation: o2 {:?}, he {:?}, p {:?} Pa\n",
            sat.gas.o2, sat.gas.he, sat.ambient_pa
        ));
    }
    s.push_str("breakpoints: [\n");
    for (i, (t, p)) in profile.times_s.iter().zip(&profile.ambient_pa).enumerate() {
        s.push_str(&format!("    {i}: t {t:?} s, p {p:?} Pa"));
        if let Some(g) = profile.gas.get(i) {
            s.push_str(&format!(", o2 {:?}, he {:?}", g.o2, g.he));
        }
        s.push('\n');
    }
    s.push_str("]\n");
    s
}

/// The first line where two canonical texts differ, with the path of fields that leads to it
/// (from the indentation of the `Debug` output): "surface_tension is `0.05` here, `0.07` in the
/// checkpoint".
fn first_difference(here: &str, there: &str) -> Option<String> {
    let (a, b): (Vec<&str>, Vec<&str>) = (here.lines().collect(), there.lines().collect());
    // the open blocks above the current line: (indentation, key)
    let mut stack: Vec<(usize, String)> = Vec::new();
    for i in 0..a.len().max(b.len()) {
        let (x, y) = (a.get(i).copied(), b.get(i).copied());
        let line = x.or(y).unwrap_or("");
        let indent = line.len() - line.trim_start().len();
        let t = line.trim();
        let key = t.split_once(": ").map(|(k, _)| k.to_string());
        while stack.last().is_some_and(|(d, _)| *d >= indent) {
            stack.pop();
        }
        if x != y {
            let mut path: Vec<String> = stack
                .iter()
                .map(|(_, k)| k.clone())
                .filter(|k| !k.is_empty())
                .collect();
            if let Some(k) = &key {
                path.push(k.clone());
            }
            let shown = |l: Option<&str>| match l {
                Some(l) => format!("`{}`", l.trim().trim_end_matches(',')),
                None => "nothing (the text ends)".to_string(),
            };
            let at = if path.is_empty() {
                format!("line {}", i + 1)
            } else {
                path.join(".")
            };
            return Some(format!(
                "{at}: {} here, {} in the checkpoint",
                shown(x),
                shown(y)
            ));
        }
        if t.ends_with('{') || t.ends_with('[') || t.ends_with('(') {
            stack.push((indent, key.unwrap_or_default()));
        }
    }
    None
}

// ---------------------------------------------------------------------------------------------
// state

/// The whole state of a run after a complete step (see the module documentation).
#[derive(Debug, Clone)]
pub struct RunState {
    time: f64,
    fields: Vec<Vec<f64>>,
    bubbles: Vec<Bubble>,
    inflow: f64,
    initial_total: f64,
    displaced_gas: f64,
    displaced: Vec<Displaced>,
    excluded: Vec<usize>,
    nuclei: Vec<Option<usize>>,
    /// Per occupied cell of the nucleus pool: the largest crushing pressure seen, Pa (VPM
    /// skins; all 0 without).
    crushing: Vec<f64>,
    steps_state: Vec<StepExchange>,
    /// The field error estimate's history: per gas the last step's change, and its length.
    last_change: Vec<Vec<f64>>,
    last_dt: f64,
    looping: LoopState,
}

impl RunState {
    /// The state of `sim` with the time loop's `looping` state.
    pub(super) fn capture(sim: &Simulation, looping: LoopState) -> RunState {
        RunState {
            time: sim.time,
            fields: sim.fields.to_vecs(),
            bubbles: sim.bubbles.clone(),
            inflow: sim.inflow,
            initial_total: sim.initial_total,
            displaced_gas: sim.displaced_gas,
            displaced: sim.displaced.clone(),
            excluded: sim.grid.excluded_cells(),
            nuclei: sim.nuclei.entries().iter().map(|e| e.bubble).collect(),
            crushing: sim.nuclei.crushing().to_vec(),
            steps_state: sim.steps_state.clone(),
            last_change: sim.last_change.clone(),
            last_dt: sim.last_dt,
            looping,
        }
    }

    /// Simulated time of the state, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken up to the state (explicit, implicit).
    pub fn steps(&self) -> (usize, usize) {
        self.looping.log.steps
    }

    /// Rebuild the simulation of `params` and `profile` (which must be the inputs the state came
    /// from: [`read`] checks) in this state. Sizes and indices are checked against the rebuilt
    /// grid, gases and nuclei; a mismatch is a corrupt checkpoint (the message says what).
    fn restore<'a>(
        self,
        params: &'a PhantomParams,
        profile: &PressureHistory,
    ) -> Result<(Simulation<'a>, LoopState), String> {
        let mut sim = Simulation::new(params, profile).map_err(|e| e.to_string())?;
        let cells = sim.grid.len();
        let ng = sim.gases().len();
        let nb = self.bubbles.len();
        if self.fields.len() != ng || self.fields.iter().any(|f| f.len() != cells) {
            return Err(format!(
                "it holds {} gas fields of {} cells; this run has {ng} of {cells}",
                self.fields.len(),
                self.fields.first().map_or(0, |f| f.len())
            ));
        }
        for (i, b) in self.bubbles.iter().enumerate() {
            let fate_ok = match b.fate {
                BubbleFate::Merged { into, .. } => into < nb,
                _ => true,
            };
            let finite = b.position.iter().all(|x| x.is_finite())
                && sim.grid.contains(b.position)
                && b.radius.is_finite()
                && b.radius >= 0.0
                && b.moles.iter().all(|m| m.is_finite());
            if b.id != i || b.moles.len() != ng || !fate_ok || !finite {
                return Err(format!("bubble {i} is inconsistent"));
            }
        }
        let pool = sim.nuclei.entries().len();
        if self.nuclei.len() != pool || self.nuclei.iter().flatten().any(|&b| b >= nb) {
            return Err(format!(
                "it holds {} nuclei; this run has {pool}",
                self.nuclei.len()
            ));
        }
        let in_grid = |c: &usize| *c < cells && sim.grid.inside_phantom(*c);
        if !self.excluded.iter().all(in_grid)
            || self.excluded.windows(2).any(|w| w[0] >= w[1])
            || self.displaced.len() > nb
            || self.displaced.iter().any(|d| !d.cells.iter().all(in_grid))
        {
            return Err("its displaced cells are not cells of this grid".into());
        }
        let lp = &self.looping;
        if self.steps_state.len() > nb
            || lp.tensions.len() != nb
            || lp.fluxes.len() != nb
            || lp.fluxes.iter().any(|f| f.len() != ng)
            || lp.log.ending != Ending::Completed
        {
            return Err("its step state does not fit its bubbles".into());
        }
        if lp.loading.last.len() != ng || lp.loading.before.len() != ng {
            return Err("its loading history does not fit its gases".into());
        }
        // the cells held out of the gel: give back those set-up took, take the saved ones
        let now = sim.grid.excluded_cells();
        let give: Vec<usize> = now
            .iter()
            .copied()
            .filter(|c| self.excluded.binary_search(c).is_err())
            .collect();
        sim.grid.set_excluded(&give, false);
        sim.grid.set_excluded(&self.excluded, true);
        let mut nuclei = std::mem::take(&mut sim.nuclei);
        for (i, b) in self.nuclei.iter().enumerate() {
            if let Some(b) = b {
                nuclei.activate(i, *b);
            }
        }
        nuclei.restore_crushing(&self.crushing)?;
        sim.nuclei = nuclei;
        sim.time = self.time;
        sim.fields = Fields::new(self.fields, sim.grid.n[0] * sim.grid.n[1]);
        sim.tension_bound = None;
        sim.bubbles = self.bubbles;
        sim.inflow = self.inflow;
        sim.initial_total = self.initial_total;
        sim.displaced_gas = self.displaced_gas;
        sim.displaced = self.displaced;
        sim.steps_state = self.steps_state;
        if !self.last_change.is_empty()
            && (self.last_change.len() != sim.fields.len()
                || self.last_change.iter().any(|f| f.len() != cells))
        {
            return Err(format!(
                "it holds a field-error history of {} fields; this run has {} of {cells} cells",
                self.last_change.len(),
                sim.fields.len()
            ));
        }
        sim.last_change = self.last_change;
        sim.last_dt = self.last_dt;
        Ok((sim, self.looping))
    }
}

/// A checkpoint read back: the inputs it belongs to, the run's state and the frames recorded
/// up to it.
#[derive(Debug, Clone)]
pub struct Checkpoint {
    /// The decophantom version that wrote it.
    pub crate_version: String,
    /// Its inputs.
    pub inputs: Inputs,
    /// The run's state.
    pub state: RunState,
    /// The frames recorded up to the state.
    pub frames: Vec<Frame>,
}

impl Checkpoint {
    /// Continue the run to its end: rebuild the simulation of `params` and `profile` in the
    /// saved state and run it on; `observer` receives only the frames after the checkpoint
    /// (the earlier ones are [`Checkpoint::frames`]). `file` names the checkpoint in errors.
    pub fn resume(
        self,
        params: &PhantomParams,
        profile: &PressureHistory,
        observer: &mut dyn Observer,
        file: &Path,
    ) -> Result<RunSummary, Error> {
        let (mut sim, looping) = self
            .state
            .restore(params, profile)
            .map_err(|m| corrupt(file, &m))?;
        sim.run_from(profile, observer, Some(looping))
    }
}

// ---------------------------------------------------------------------------------------------
// encoding

struct Enc {
    buf: Vec<u8>,
}

impl Enc {
    fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }
    fn u64(&mut self, v: u64) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    fn usize(&mut self, v: usize) {
        self.u64(v as u64);
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn str(&mut self, s: &str) {
        self.usize(s.len());
        self.buf.extend_from_slice(s.as_bytes());
    }
    fn f64s(&mut self, v: &[f64]) {
        self.usize(v.len());
        self.buf.reserve(v.len() * 8);
        for x in v {
            self.f64(*x);
        }
    }
    fn usizes(&mut self, v: &[usize]) {
        self.usize(v.len());
        for x in v {
            self.usize(*x);
        }
    }
    fn point(&mut self, p: [f64; 3]) {
        for x in p {
            self.f64(x);
        }
    }
    fn bubble(&mut self, b: &Bubble) {
        self.usize(b.id);
        self.point(b.position);
        self.f64(b.initial_radius);
        self.f64(b.initial_ambient);
        self.f64s(&b.moles);
        self.f64(b.radius);
        match b.fate {
            BubbleFate::Active => self.u8(0),
            BubbleFate::Dissolved(t) => {
                self.u8(1);
                self.f64(t);
            }
            BubbleFate::Merged { into, time } => {
                self.u8(2);
                self.usize(into);
                self.f64(time);
            }
        }
    }
    fn event(&mut self, e: &Event) {
        match *e {
            Event::Coalesced {
                time,
                into,
                absorbed,
            } => {
                self.u8(0);
                self.f64(time);
                self.usize(into);
                self.usize(absorbed);
            }
            Event::Dissolved { time, bubble } => {
                self.u8(1);
                self.f64(time);
                self.usize(bubble);
            }
        }
    }
    fn frame(&mut self, f: &Frame) {
        self.f64(f.time);
        self.f64(f.ambient);
        self.usize(f.bubbles.len());
        for b in &f.bubbles {
            self.usize(b.id);
            self.f64(b.radius);
            self.f64(b.initial_radius);
            self.f64(b.volume);
            self.f64(b.area);
            self.f64s(&b.moles);
            self.f64(b.gel_tension);
            self.point(b.position);
        }
        self.f64(f.max_supersaturation);
        self.f64s(&f.grid_moles);
    }
    fn state(&mut self, s: &RunState) {
        self.f64(s.time);
        self.usize(s.fields.len());
        for f in &s.fields {
            self.f64s(f);
        }
        self.usize(s.bubbles.len());
        for b in &s.bubbles {
            self.bubble(b);
        }
        self.f64(s.inflow);
        self.f64(s.initial_total);
        self.f64(s.displaced_gas);
        self.usize(s.displaced.len());
        for d in &s.displaced {
            self.f64(d.radius);
            self.point(d.centre);
            self.usizes(&d.cells);
            self.f64(d.wall_speed);
            self.f64(d.last.0);
            self.f64(d.last.1);
        }
        self.usizes(&s.excluded);
        self.usize(s.nuclei.len());
        for n in &s.nuclei {
            match n {
                None => self.u8(0),
                Some(b) => {
                    self.u8(1);
                    self.usize(*b);
                }
            }
        }
        self.f64s(&s.crushing);
        self.usize(s.steps_state.len());
        for st in &s.steps_state {
            self.f64s(&st.start);
            self.f64s(&st.taken);
            self.f64s(&st.flux);
            self.u8(st.open as u8);
        }
        self.usize(s.last_change.len());
        for f in &s.last_change {
            self.f64s(f);
        }
        self.f64(s.last_dt);
        let lp = &s.looping;
        let log = &lp.log;
        self.f64(log.max_radius.0);
        self.f64(log.max_radius.1);
        self.usize(log.max_radius.2);
        self.f64(log.peak_volume.0);
        self.f64(log.peak_volume.1);
        self.f64(log.min_concentration);
        self.usize(log.steps.0);
        self.usize(log.steps.1);
        self.usize(log.events.len());
        for e in &log.events {
            self.event(e);
        }
        self.f64(log.next_record);
        self.f64(lp.dt_prev);
        self.f64(lp.bubble_dt);
        self.f64(lp.field_dt);
        self.f64(lp.loading_dt);
        self.f64s(&lp.loading.last);
        self.f64(lp.loading.last_dt);
        self.f64s(&lp.loading.before);
        self.f64(lp.loading.before_dt);
        self.f64s(&lp.tensions);
        self.usize(lp.fluxes.len());
        for f in &lp.fluxes {
            self.f64s(f);
        }
    }
}

/// A new buffer with the header of a file of kind `magic` (payload length set by [`seal`]).
fn open_frame(magic: &[u8; 8], capacity: usize) -> Enc {
    let mut e = Enc {
        buf: Vec::with_capacity(capacity + 64),
    };
    e.buf.extend_from_slice(magic);
    e.buf.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    e.u64(0); // payload length, set by `seal`
    e.str(env!("CARGO_PKG_VERSION"));
    e
}

/// Set the payload length and append the checksum.
fn seal(mut e: Enc) -> Vec<u8> {
    let payload = (e.buf.len() - 20) as u64;
    e.buf[12..20].copy_from_slice(&payload.to_le_bytes());
    let sum = fnv1a(&e.buf);
    e.u64(sum);
    e.buf
}

/// The bytes of a checkpoint of `state` (with the `frames` recorded up to it) for `inputs`.
pub fn encode(inputs: &Inputs, state: &RunState, frames: &[Frame]) -> Vec<u8> {
    let cells: usize = state.fields.iter().map(|f| f.len()).sum::<usize>()
        + state.last_change.iter().map(|f| f.len()).sum::<usize>();
    let mut e = open_frame(MAGIC, cells * 8 + frames.len() * 128 + 4096);
    e.usize(inputs.sections.len());
    for s in &inputs.sections {
        e.str(&s.name);
        e.u64(s.hash);
        e.str(&s.text);
    }
    e.state(state);
    e.usize(frames.len());
    for f in frames {
        e.frame(f);
    }
    seal(e)
}

/// The first eight bytes of a finished run's result file ([`encode_result`]).
pub const RESULT_MAGIC: &[u8; 8] = b"DCPHRSLT";

/// The bytes of a finished run's result: its summary and frames (the same framing and
/// encodings as a checkpoint; a journal keeps finished runs this way, [`decode_result`]).
pub fn encode_result(summary: &RunSummary, frames: &[Frame]) -> Vec<u8> {
    let mut e = open_frame(RESULT_MAGIC, frames.len() * 128 + 4096);
    e.usize(summary.gases.len());
    for g in &summary.gases {
        e.str(g.name());
    }
    e.f64(summary.max_radius.0);
    e.f64(summary.max_radius.1);
    e.usize(summary.max_radius.2);
    e.f64s(&summary.final_radii);
    e.f64(summary.peak_total_volume.0);
    e.f64(summary.peak_total_volume.1);
    e.f64(summary.gas_balance_error);
    e.f64(summary.min_concentration);
    e.usize(summary.steps.0);
    e.usize(summary.steps.1);
    e.f64(summary.end_time);
    match &summary.ending {
        Ending::Completed => e.u8(0),
        Ending::Interrupted { time } => {
            e.u8(1);
            e.f64(*time);
        }
        Ending::BubbleReachedFace { bubble, face, time } => {
            e.u8(2);
            e.usize(*bubble);
            e.str(face.name());
            e.f64(*time);
        }
    }
    e.usize(summary.events.len());
    for ev in &summary.events {
        e.event(ev);
    }
    e.usize(summary.cells);
    e.usize(frames.len());
    for f in frames {
        e.frame(f);
    }
    seal(e)
}

struct Dec<'a> {
    buf: &'a [u8],
    pos: usize,
}

type Res<T> = Result<T, String>;

impl Dec<'_> {
    fn take(&mut self, n: usize) -> Res<&[u8]> {
        if self.buf.len() - self.pos < n {
            return Err(format!("it ends early (byte {})", self.pos));
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn u8(&mut self) -> Res<u8> {
        Ok(self.take(1)?[0])
    }
    fn u64(&mut self) -> Res<u64> {
        let b = self.take(8)?;
        Ok(u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }
    fn usize(&mut self) -> Res<usize> {
        let v = self.u64()?;
        usize::try_from(v).map_err(|_| format!("a count of {v} at byte {}", self.pos))
    }
    /// A length of a sequence whose elements take at least `min_size` bytes each: at most what
    /// the bytes left can hold (so a corrupt length never allocates).
    fn len(&mut self, min_size: usize) -> Res<usize> {
        let n = self.usize()?;
        if n.saturating_mul(min_size.max(1)) > self.buf.len() - self.pos {
            return Err(format!(
                "a length of {n} at byte {} is more than the file holds",
                self.pos
            ));
        }
        Ok(n)
    }
    fn f64(&mut self) -> Res<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn bool(&mut self) -> Res<bool> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            x => Err(format!("a flag of {x} at byte {}", self.pos)),
        }
    }
    fn str(&mut self) -> Res<String> {
        let n = self.len(1)?;
        let b = self.take(n)?;
        String::from_utf8(b.to_vec())
            .map_err(|_| format!("text that is not UTF-8 at byte {}", self.pos))
    }
    fn f64s(&mut self) -> Res<Vec<f64>> {
        let n = self.len(8)?;
        let b = self.take(n * 8)?;
        Ok(b.chunks_exact(8)
            .map(|c| f64::from_bits(u64::from_le_bytes(c.try_into().expect("8 bytes"))))
            .collect())
    }
    fn gas_array(&mut self) -> Res<[f64; Gas::ALL.len()]> {
        let v = self.f64s()?;
        v.try_into()
            .map_err(|_| format!("a per-gas array of the wrong length at byte {}", self.pos))
    }
    fn usizes(&mut self) -> Res<Vec<usize>> {
        let n = self.len(8)?;
        (0..n).map(|_| self.usize()).collect()
    }
    fn point(&mut self) -> Res<[f64; 3]> {
        Ok([self.f64()?, self.f64()?, self.f64()?])
    }
    fn bubble(&mut self) -> Res<Bubble> {
        let id = self.usize()?;
        let position = self.point()?;
        let initial_radius = self.f64()?;
        let initial_ambient = self.f64()?;
        let moles = self.f64s()?;
        let radius = self.f64()?;
        let fate = match self.u8()? {
            0 => BubbleFate::Active,
            1 => BubbleFate::Dissolved(self.f64()?),
            2 => BubbleFate::Merged {
                into: self.usize()?,
                time: self.f64()?,
            },
            x => return Err(format!("a bubble fate of {x} at byte {}", self.pos)),
        };
        Ok(Bubble {
            id,
            position,
            initial_radius,
            initial_ambient,
            moles,
            radius,
            fate,
        })
    }
    fn event(&mut self) -> Res<Event> {
        match self.u8()? {
            0 => Ok(Event::Coalesced {
                time: self.f64()?,
                into: self.usize()?,
                absorbed: self.usize()?,
            }),
            1 => Ok(Event::Dissolved {
                time: self.f64()?,
                bubble: self.usize()?,
            }),
            x => Err(format!("an event kind of {x} at byte {}", self.pos)),
        }
    }
    fn frame(&mut self) -> Res<Frame> {
        let time = self.f64()?;
        let ambient = self.f64()?;
        let n = self.len(8 * 10)?;
        let mut bubbles = Vec::with_capacity(n);
        for _ in 0..n {
            bubbles.push(BubbleFrame {
                id: self.usize()?,
                radius: self.f64()?,
                initial_radius: self.f64()?,
                volume: self.f64()?,
                area: self.f64()?,
                moles: self.f64s()?,
                gel_tension: self.f64()?,
                position: self.point()?,
            });
        }
        Ok(Frame {
            time,
            ambient,
            bubbles,
            max_supersaturation: self.f64()?,
            grid_moles: self.f64s()?,
        })
    }
    fn state(&mut self) -> Res<RunState> {
        let time = self.f64()?;
        let n = self.len(8)?;
        let fields = (0..n).map(|_| self.f64s()).collect::<Res<Vec<_>>>()?;
        let n = self.len(8 * 8)?;
        let bubbles = (0..n).map(|_| self.bubble()).collect::<Res<Vec<_>>>()?;
        let inflow = self.f64()?;
        let initial_total = self.f64()?;
        let displaced_gas = self.f64()?;
        let n = self.len(8 * 8)?;
        let mut displaced = Vec::with_capacity(n);
        for _ in 0..n {
            displaced.push(Displaced {
                radius: self.f64()?,
                centre: self.point()?,
                cells: self.usizes()?,
                wall_speed: self.f64()?,
                last: (self.f64()?, self.f64()?),
            });
        }
        let excluded = self.usizes()?;
        let n = self.len(1)?;
        let mut nuclei = Vec::with_capacity(n);
        for _ in 0..n {
            nuclei.push(match self.u8()? {
                0 => None,
                1 => Some(self.usize()?),
                x => return Err(format!("a nucleus state of {x} at byte {}", self.pos)),
            });
        }
        let crushing = self.f64s()?;
        let n = self.len(3 * 8 + 1)?;
        let mut steps_state = Vec::with_capacity(n);
        for _ in 0..n {
            steps_state.push(StepExchange {
                start: self.gas_array()?,
                taken: self.gas_array()?,
                flux: self.gas_array()?,
                open: self.bool()?,
            });
        }
        let n = self.len(8)?;
        let last_change = (0..n).map(|_| self.f64s()).collect::<Res<Vec<_>>>()?;
        let last_dt = self.f64()?;
        let max_radius = (self.f64()?, self.f64()?, self.usize()?);
        let peak_volume = (self.f64()?, self.f64()?);
        let min_concentration = self.f64()?;
        let steps = (self.usize()?, self.usize()?);
        let n = self.len(1 + 8 + 8)?;
        let events = (0..n).map(|_| self.event()).collect::<Res<Vec<_>>>()?;
        let next_record = self.f64()?;
        let dt_prev = self.f64()?;
        let bubble_dt = self.f64()?;
        let field_dt = self.f64()?;
        let loading_dt = self.f64()?;
        let loading = LoadingHistory {
            last: self.f64s()?,
            last_dt: self.f64()?,
            before: self.f64s()?,
            before_dt: self.f64()?,
        };
        let tensions = self.f64s()?;
        let n = self.len(8)?;
        let fluxes = (0..n).map(|_| self.f64s()).collect::<Res<Vec<_>>>()?;
        Ok(RunState {
            time,
            fields,
            bubbles,
            inflow,
            initial_total,
            displaced_gas,
            displaced,
            excluded,
            nuclei,
            crushing,
            steps_state,
            last_change,
            last_dt,
            looping: LoopState {
                log: RunLog {
                    max_radius,
                    peak_volume,
                    min_concentration,
                    steps,
                    events,
                    ending: Ending::Completed,
                    next_record,
                },
                dt_prev,
                bubble_dt,
                field_dt,
                loading_dt,
                loading,
                tensions,
                fluxes,
            },
        })
    }
}

/// Why a checkpoint cannot be read.
#[derive(Debug, Clone, PartialEq)]
pub enum DecodeError {
    /// Not a checkpoint (no magic).
    NotACheckpoint,
    /// Another format version.
    Version(u32),
    /// Truncated, or a byte changed (checksum), or inconsistent: what was found.
    Corrupt(String),
}

/// Check the framing of a file of kind `magic` (magic, format version, length, checksum) and
/// return its body (everything before the checksum).
fn unframe<'a>(magic: &[u8; 8], bytes: &'a [u8]) -> Result<&'a [u8], DecodeError> {
    if bytes.len() < 8 || &bytes[..8] != magic {
        return Err(DecodeError::NotACheckpoint);
    }
    if bytes.len() < 12 {
        return Err(DecodeError::Corrupt(
            "it ends before its format version".into(),
        ));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(DecodeError::Version(version));
    }
    if bytes.len() < 28 {
        return Err(DecodeError::Corrupt(format!(
            "it is {} bytes long, shorter than any checkpoint (truncated)",
            bytes.len()
        )));
    }
    let payload = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    let expected = payload.checked_add(28);
    if expected != Some(bytes.len() as u64) {
        return Err(DecodeError::Corrupt(format!(
            "it is {} bytes long where its header says {} (truncated or appended to)",
            bytes.len(),
            expected.map_or("more than 2^64".into(), |e| e.to_string())
        )));
    }
    let (body, sum) = bytes.split_at(bytes.len() - 8);
    if fnv1a(body) != u64::from_le_bytes(sum.try_into().expect("8 bytes")) {
        return Err(DecodeError::Corrupt(
            "its checksum does not match its contents (a byte was changed)".into(),
        ));
    }
    Ok(body)
}

/// Read a finished run's result (the inverse of [`encode_result`]); `None` unless it is whole,
/// of this format and of this decophantom version.
pub fn decode_result(bytes: &[u8]) -> Option<(RunSummary, Vec<Frame>)> {
    let body = unframe(RESULT_MAGIC, bytes).ok()?;
    let mut d = Dec { buf: body, pos: 20 };
    let read = |d: &mut Dec| -> Res<(RunSummary, Vec<Frame>)> {
        if d.str()? != env!("CARGO_PKG_VERSION") {
            return Err("another version".into());
        }
        let n = d.len(8)?;
        let mut gases = Vec::with_capacity(n);
        for _ in 0..n {
            let name = d.str()?;
            let g = Gas::ALL
                .iter()
                .find(|g| g.name() == name)
                .ok_or("an unknown gas")?;
            gases.push(*g);
        }
        let max_radius = (d.f64()?, d.f64()?, d.usize()?);
        let final_radii = d.f64s()?;
        let peak_total_volume = (d.f64()?, d.f64()?);
        let gas_balance_error = d.f64()?;
        let min_concentration = d.f64()?;
        let steps = (d.usize()?, d.usize()?);
        let end_time = d.f64()?;
        let ending = match d.u8()? {
            0 => Ending::Completed,
            1 => Ending::Interrupted { time: d.f64()? },
            2 => {
                let bubble = d.usize()?;
                let name = d.str()?;
                let face = [
                    Face::XMinus,
                    Face::XPlus,
                    Face::YMinus,
                    Face::YPlus,
                    Face::Bottom,
                    Face::Top,
                    Face::Side,
                ]
                .into_iter()
                .find(|f| f.name() == name)
                .ok_or("an unknown face")?;
                Ending::BubbleReachedFace {
                    bubble,
                    face,
                    time: d.f64()?,
                }
            }
            _ => return Err("an unknown ending".into()),
        };
        let n = d.len(1 + 8 + 8)?;
        let events = (0..n).map(|_| d.event()).collect::<Res<Vec<_>>>()?;
        let cells = d.usize()?;
        let n = d.len(8 * 6)?;
        let frames = (0..n).map(|_| d.frame()).collect::<Res<Vec<_>>>()?;
        if d.pos != d.buf.len() {
            return Err("bytes left over".into());
        }
        Ok((
            RunSummary {
                gases,
                max_radius,
                final_radii,
                peak_total_volume,
                gas_balance_error,
                min_concentration,
                steps,
                end_time,
                ending,
                events,
                cells,
            },
            frames,
        ))
    };
    read(&mut d).ok()
}

/// Read the bytes of a checkpoint (the inverse of [`encode`]). Never panics: every length and
/// tag is checked.
pub fn decode(bytes: &[u8]) -> Result<Checkpoint, DecodeError> {
    let body = unframe(MAGIC, bytes)?;
    let mut d = Dec { buf: body, pos: 20 };
    let read = |d: &mut Dec| -> Res<Checkpoint> {
        let crate_version = d.str()?;
        let n = d.len(8 * 3)?;
        let mut sections = Vec::with_capacity(n);
        for _ in 0..n {
            sections.push(InputSection {
                name: d.str()?,
                hash: d.u64()?,
                text: d.str()?,
            });
        }
        let state = d.state()?;
        let n = d.len(8 * 6)?;
        let frames = (0..n).map(|_| d.frame()).collect::<Res<Vec<_>>>()?;
        if d.pos != d.buf.len() {
            return Err(format!("{} bytes are left over", d.buf.len() - d.pos));
        }
        Ok(Checkpoint {
            crate_version,
            inputs: Inputs { sections },
            state,
            frames,
        })
    };
    read(&mut d).map_err(DecodeError::Corrupt)
}

// ---------------------------------------------------------------------------------------------
// files

fn refused(file: &Path, message: String) -> Error {
    Error::Input(InputError::new(message).in_file(file).field("--resume"))
}

fn corrupt(file: &Path, what: &str) -> Error {
    refused(
        file,
        format!("the checkpoint is truncated or corrupt: {what}; it cannot be resumed: start the run afresh without --resume"),
    )
}

/// The checkpoint file that `--resume PATH` names: `PATH` itself when it is a file, else
/// `PATH/checkpoint.dcp`.
pub fn locate(path: &Path) -> PathBuf {
    if path.is_dir() {
        path.join(FILE_NAME)
    } else {
        path.to_path_buf()
    }
}

/// Where `simulate --out OUT --checkpoint-every …` keeps its checkpoint: the folder
/// `OUT.checkpoint` beside the output folder (the output folder itself is written whole at the
/// end, so it cannot hold a file during the run), file [`FILE_NAME`].
pub fn default_path(out: &Path) -> PathBuf {
    let mut name = out
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_else(|| "out".into());
    name.push(".checkpoint");
    out.with_file_name(name).join(FILE_NAME)
}

/// Read the checkpoint `file` for a run of `inputs`. Bad input (exit 2) naming the file when
/// it is missing, not a checkpoint, of another format or decophantom version, truncated,
/// corrupt, or of other inputs (and then what differs).
pub fn read(file: &Path, inputs: &Inputs) -> Result<Checkpoint, Error> {
    let bytes = std::fs::read(file).map_err(|e| {
        refused(
            file,
            format!("cannot read the checkpoint: {e}; give the folder or file a checkpointed run wrote (OUT.checkpoint)"),
        )
    })?;
    let cp = decode(&bytes).map_err(|e| match e {
        DecodeError::NotACheckpoint => refused(
            file,
            "not a decophantom checkpoint (it does not start with DCPHCKPT)".into(),
        ),
        DecodeError::Version(v) => refused(
            file,
            format!("the checkpoint has format version {v}; this decophantom reads version {FORMAT_VERSION} only: start the run afresh without --resume"),
        ),
        DecodeError::Corrupt(m) => corrupt(file, &m),
    })?;
    let here = env!("CARGO_PKG_VERSION");
    if cp.crate_version != here {
        return Err(refused(
            file,
            format!("the checkpoint was written by decophantom {}, this is {here}; a run resumes only in the version that started it (its numerics may differ): start afresh without --resume", cp.crate_version),
        ));
    }
    if let Some(d) = inputs.difference(&cp.inputs) {
        return Err(refused(
            file,
            format!("the checkpoint belongs to other inputs: {d}; resume with the profile, phantom and options of the checkpointed run, or start afresh without --resume"),
        ));
    }
    Ok(cp)
}

/// Check the place of a checkpoint before the run (its folder is created at the first
/// checkpoint, so a run refused before it writes nothing): the folder must be a folder or
/// absent, and a file already there must be a checkpoint (it is replaced by this run's), never
/// a user's file. Errors are bad input naming `--checkpoint-every` (exit 2).
pub fn prepare(file: &Path) -> Result<(), Error> {
    let err =
        |m: String| Error::Input(InputError::new(m).in_file(file).field("--checkpoint-every"));
    if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
        if dir.exists() && !dir.is_dir() {
            return Err(err(format!(
                "{} exists and is not a folder; move it, or choose another --out",
                dir.display()
            )));
        }
    }
    match std::fs::symlink_metadata(file) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(Error::io(file, e)),
        Ok(m) if !m.is_file() => Err(err(
            "exists and is not a checkpoint file; move it, or choose another --out".into(),
        )),
        Ok(_) => {
            use std::io::Read as _;
            let mut head = [0u8; 8];
            let is_ours = std::fs::File::open(file)
                .and_then(|mut f| f.read_exact(&mut head))
                .is_ok()
                && &head == MAGIC;
            if is_ours {
                Ok(())
            } else {
                Err(err(
                    "exists and is not a decophantom checkpoint; it would be overwritten: move it, or choose another --out".into(),
                ))
            }
        }
    }
}

/// Remove a checkpoint file this tool wrote (checked by its magic) and its folder if that is
/// then empty; best effort (a completed run no longer needs it).
pub fn remove(file: &Path) {
    use std::io::Read as _;
    // temporary files of killed writers first (`.checkpoint.dcp.tmp-PID-N`)
    let _ = crate::report::output::check_file_target(file, &[]);
    let mut head = [0u8; 8];
    let ours = std::fs::File::open(file)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && &head == MAGIC;
    if ours && std::fs::remove_file(file).is_ok() {
        if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
            let _ = std::fs::remove_dir(dir);
        }
    }
}

/// Parse a wall-clock interval: a number with a unit `s`, `min` or `h` (`60s`, `5min`, `1.5h`).
/// Positive and at most 30 days. A bare number is refused: `5` could mean seconds or minutes.
pub fn parse_interval(text: &str) -> Result<Duration, InputError> {
    let t = text.trim();
    let err = || {
        InputError::new(format!(
            "'{text}' is not a wall-clock interval: give a positive number with a unit, e.g. 60s, 5min or 1h"
        ))
        .in_file("<command line>")
        .field("--checkpoint-every")
    };
    let split = t
        .find(|c: char| {
            !(c.is_ascii_digit() || c == '.' || c == 'e' || c == 'E' || c == '+' || c == '-')
        })
        .unwrap_or(t.len());
    // `e` of an exponent vs a unit: units here never start with e
    let (num, unit) = t.split_at(split);
    let factor = match unit.trim() {
        "" => {
            return Err(InputError::new(format!(
                "'{text}' has no unit: give a positive number with a unit, e.g. 60s, 5min or 1h"
            ))
            .in_file("<command line>")
            .field("--checkpoint-every"))
        }
        "s" | "sec" => 1.0,
        "min" | "m" => 60.0,
        "h" => 3600.0,
        _ => return Err(err()),
    };
    let v: f64 = num.parse().map_err(|_| err())?;
    let secs = v * factor;
    if secs > 30.0 * 86_400.0 && secs.is_finite() {
        return Err(InputError::new(format!(
            "'{text}' is {} s, longer than the 30 days a checkpoint interval may be",
            crate::error::num(secs)
        ))
        .in_file("<command line>")
        .field("--checkpoint-every"));
    }
    if !(secs > 0.0 && secs.is_finite()) {
        return Err(err());
    }
    Ok(Duration::from_secs_f64(secs))
}

// ---------------------------------------------------------------------------------------------
// the policy

/// What a [`Checkpointer`] has done.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stats {
    /// The checkpoint file.
    pub path: PathBuf,
    /// Checkpoints written.
    pub written: usize,
    /// Size of the last one, bytes.
    pub bytes: usize,
    /// Wall time spent encoding and writing them, s.
    pub seconds: f64,
    /// Simulated time of the last one, s.
    pub time: f64,
}

/// Decides when a run saves its state and writes it: every `every` of wall time, after step
/// `at_step` (then the run stops, as a kill would stop it: for tests), and once after a stop
/// request (Ctrl-C), before the run is let stop. The observer of a checkpointed run asks
/// [`Checkpointer::due`] and [`Checkpointer::let_stop`] and hands its frames to
/// [`Checkpointer::write`].
#[derive(Debug)]
pub struct Checkpointer {
    inputs: Inputs,
    guard: Vec<PathBuf>,
    every: Option<Duration>,
    at_step: Option<usize>,
    last: Instant,
    saved_on_stop: bool,
    pending_stop: bool,
    halt: bool,
    /// What it has done.
    pub stats: Stats,
}

impl Checkpointer {
    /// Checkpoints of a run of `inputs` into `path` (never over one of the `guard` files: the
    /// run's inputs), every `every` of wall time and/or after step `at_step`.
    pub fn new(
        path: PathBuf,
        inputs: Inputs,
        guard: Vec<PathBuf>,
        every: Option<Duration>,
        at_step: Option<usize>,
    ) -> Self {
        Checkpointer {
            inputs,
            guard,
            every,
            at_step,
            last: Instant::now(),
            saved_on_stop: false,
            pending_stop: false,
            halt: false,
            stats: Stats {
                path,
                ..Stats::default()
            },
        }
    }

    /// Whether to save after step `step`; `stop_requested`: the user asked the run to stop.
    pub fn due(&mut self, step: usize, stop_requested: bool) -> bool {
        self.pending_stop = stop_requested && !self.saved_on_stop;
        self.pending_stop
            || self.at_step == Some(step)
            || self.every.is_some_and(|e| self.last.elapsed() >= e)
    }

    /// Whether the run may stop now: after a stop request only once the state has been saved
    /// (so Ctrl-C costs at most one more step), and after the test hook's checkpoint.
    pub fn let_stop(&self, stop_requested: bool) -> bool {
        (stop_requested && self.saved_on_stop) || self.halt
    }

    /// Write the checkpoint of `state` with the `frames` recorded so far (atomically: a
    /// temporary file beside it, flushed, renamed over it).
    pub fn write(&mut self, state: &RunState, frames: &[Frame]) -> Result<(), Error> {
        let start = Instant::now();
        let bytes = encode(&self.inputs, state, frames);
        let guard: Vec<&Path> = self.guard.iter().map(|p| p.as_path()).collect();
        if let Some(dir) = self
            .stats
            .path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
        {
            std::fs::create_dir_all(dir).map_err(Error::io_at(dir))?;
        }
        crate::report::output::write_file_atomic_with_inputs(&self.stats.path, &bytes, &guard)?;
        if let Some(dir) = self
            .stats
            .path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
        {
            // the rename itself to disk (best effort: not every platform opens folders)
            if let Ok(d) = std::fs::File::open(dir) {
                let _ = d.sync_all();
            }
        }
        self.stats.written += 1;
        self.stats.bytes = bytes.len();
        self.stats.seconds += start.elapsed().as_secs_f64();
        self.stats.time = state.time;
        if self.pending_stop {
            self.saved_on_stop = true;
        }
        if self.at_step == Some(state.looping.log.steps.0 + state.looping.log.steps.1) {
            self.halt = true;
        }
        self.last = Instant::now();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_parse_with_their_units() {
        let s = |t: &str| parse_interval(t).map(|d| d.as_secs_f64());
        assert_eq!(s("60s").unwrap(), 60.0);
        assert_eq!(s("5min").unwrap(), 300.0);
        assert_eq!(s("1.5h").unwrap(), 5400.0);
        // a bare number has no unit: refused (seconds or minutes?)
        assert!(parse_interval("90")
            .unwrap_err()
            .to_string()
            .contains("no unit"));
        assert_eq!(s(" 2 min ").unwrap(), 120.0);
        assert_eq!(s("0.25s").unwrap(), 0.25);
        for bad in [
            "",
            "0s",
            "-5s",
            "nan",
            "inf",
            "5 parsecs",
            "31d",
            "1e9h",
            "s",
        ] {
            let e = parse_interval(bad).unwrap_err();
            assert_eq!(e.field.as_deref(), Some("--checkpoint-every"), "{bad}");
        }
        // too long is said as such, not as a malformed interval
        let e = parse_interval("1000000h").unwrap_err().to_string();
        assert!(e.contains("longer than the 30 days"), "{e}");
        assert!(s("720h").is_ok());
    }

    #[test]
    fn fnv1a_matches_the_reference_values() {
        // the published FNV-1a 64 test vectors
        assert_eq!(fnv1a(b""), 0xcbf29ce484222325);
        assert_eq!(fnv1a(b"a"), 0xaf63dc4c8601ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x85944171f73967e8);
    }

    #[test]
    fn the_first_difference_is_named_by_its_field_path() {
        let a = "P {\n    name: \"\",\n    gases: [\n        G {\n            diffusivity: 2e-9,\n        },\n    ],\n    surface_tension: 0.07,\n}\n";
        let b = a.replace("2e-9", "3e-9");
        assert_eq!(
            first_difference(a, &b).unwrap(),
            "gases.diffusivity: `diffusivity: 2e-9` here, `diffusivity: 3e-9` in the checkpoint"
        );
        let c = a.replace("0.07", "0.05");
        assert_eq!(
            first_difference(a, &c).unwrap(),
            "surface_tension: `surface_tension: 0.07` here, `surface_tension: 0.05` in the checkpoint"
        );
        assert_eq!(first_difference(a, a), None);
    }
}
