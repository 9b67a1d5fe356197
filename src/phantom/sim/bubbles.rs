//! Events that change the bubbles and the grid: the gel displaced by the bubbles, coalescence,
//! nucleation, and the bubbles' placement at the start.

use super::*;
use crate::phantom::nucleation::Nucleus;
use rand::{Rng, SeedableRng};

/// Why a bubble at `p` with initial radius `r0` cannot start in `grid` ("at (x, y, z) m with
/// R0 = ... is outside the phantom or touches its x+ face ..."), `None` when it can.
pub fn bubble_outside(grid: &Grid, p: [f64; 3], r0: f64) -> Option<String> {
    // NaN positions are outside too
    let (face, d) = grid.distance_to_faces(p).find(|(_, d)| !(*d > r0))?;
    let e = grid.extent();
    Some(format!(
        "at ({:.3e}, {:.3e}, {:.3e}) m with R0 = {r0:.3e} m is outside the phantom or touches its {} face (distance {d:.3e} m); the modelled phantom spans {:.3e} × {:.3e} × {:.3e} m",
        p[0], p[1], p[2], face.name(), e[0], e[1], e[2]
    ))
}

/// Place the bubbles of `params` in `grid`: explicit positions are checked; a random
/// population is drawn with ChaCha8 from the seed, rejecting centres closer than the spacing.
pub fn place_bubbles(params: &PhantomParams, grid: &Grid) -> Result<Vec<([f64; 3], f64)>, Error> {
    let input = |m: String| Error::Input(crate::error::InputError::new(m).field("bubbles"));
    match &params.bubbles {
        BubblePlacement::Explicit(list) => {
            for (i, (p, r0)) in list.iter().enumerate() {
                if !(*r0 > 0.0) {
                    return Err(input(format!(
                        "bubble {i}: initial radius must be positive (got {r0} m)"
                    )));
                }
                if let Some(why) = bubble_outside(grid, *p, *r0) {
                    return Err(input(format!("bubble {i} {why}")));
                }
            }
            Ok(list.clone())
        }
        BubblePlacement::Random {
            count,
            initial_radius,
            min_spacing,
            margin,
            seed,
        } => {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(*seed);
            let e = grid.extent();
            let mut out: Vec<([f64; 3], f64)> = Vec::new();
            let mut tries = 0;
            while out.len() < *count {
                tries += 1;
                if tries > 100_000 {
                    return Err(input(format!(
                        "cannot place {count} bubbles {min_spacing} m apart and {margin} m from the faces; lower the count or the spacing"
                    )));
                }
                let p = [
                    rng.gen::<f64>() * e[0],
                    rng.gen::<f64>() * e[1],
                    rng.gen::<f64>() * e[2],
                ];
                if grid
                    .distance_to_faces(p)
                    .any(|(_, d)| d < margin.max(*initial_radius * 1.01))
                {
                    continue;
                }
                if out.iter().any(|(q, _)| {
                    (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt() < *min_spacing
                }) {
                    continue;
                }
                out.push((p, *initial_radius));
            }
            Ok(out)
        }
    }
}

impl Simulation<'_> {
    /// Phase 7b: bubbles displace the gel ([`displacement`], issue 8 item 5). A bubble of
    /// radius R ≥ `displace_min_cells`·h holds the cells inside R out of the gel; whenever its
    /// radius has moved by `displace_step_cells`·h since the last displacement, the gel around
    /// it is moved radially as an incompressible medium ([`displacement::remap`], out to
    /// `displace_reach`·R + 2h), the cells it has grown over leave the gel (their gel has been
    /// carried outward by the remap) and the cells it has shrunk off come back with the gel
    /// that flowed in. A dissolved or merged bubble gives its cells back at the mean of their
    /// neighbours; a merged bubble re-takes its cells about its new centre. Every change of the
    /// grid's gas here is added to `displaced_gas`, which the gas balance carries.
    pub(super) fn displace(&mut self, ambient: f64) {
        let num = self.params.numerics;
        if !num.displace_gel {
            return;
        }
        let h = self.grid.h;
        let h3 = self.grid.cell_volume();
        self.displaced
            .resize(self.bubbles.len(), Displaced::default());
        for i in 0..self.bubbles.len() {
            let b = &self.bubbles[i];
            let st = &mut self.displaced[i];
            let (r_last, t_last) = st.last;
            st.wall_speed = if self.time > t_last && b.active() && r_last > 0.0 {
                (b.radius - r_last) / (self.time - t_last)
            } else {
                0.0
            };
            st.last = (if b.active() { b.radius } else { 0.0 }, self.time);
            let st = &self.displaced[i];
            let (r_new, centre) = if b.active() && b.radius >= num.displace_min_cells * h {
                (b.radius, b.position)
            } else {
                (0.0, b.position)
            };
            let moved_centre = st.centre != centre && !st.cells.is_empty();
            if !moved_centre && (r_new - st.radius).abs() < num.displace_step_cells * h {
                continue;
            }
            if r_new == 0.0 && st.cells.is_empty() {
                self.displaced[i].radius = 0.0;
                continue;
            }
            // the gel's move (only about a fixed centre: a merge moves the centre, and its
            // rearrangement of the gel is not modelled)
            let remapped = if moved_centre || !b.active() {
                Vec::new()
            } else {
                let reach = num.displace_reach * r_new.max(st.radius) + 2.0 * h;
                // Henry's law at the wall: the gel next to the bubble
                let ps = self.balance_for(b, ambient).simulated_pressure(b.radius);
                let n = b.total_moles();
                let wall: Vec<f64> = (0..self.gases.len())
                    .map(|g| self.ostwald[g] * (b.moles[g] / n) * ps / self.rt)
                    .collect();
                displacement::remap(
                    &self.grid,
                    &self.field_views()[..self.gases.len()],
                    &wall,
                    centre,
                    st.radius,
                    r_new,
                    reach,
                )
            };
            let new_cells = if r_new > 0.0 {
                displacement::covered_cells(&self.grid, centre, r_new)
            } else {
                Vec::new()
            };
            let old_cells = std::mem::take(&mut self.displaced[i].cells);
            let mut take: Vec<usize> = Vec::new();
            let mut keep: Vec<usize> = Vec::new();
            for &idx in &new_cells {
                if old_cells.binary_search(&idx).is_ok() {
                    keep.push(idx);
                } else if !self.grid.is_excluded(idx) {
                    take.push(idx);
                }
            }
            let give: Vec<usize> = old_cells
                .iter()
                .copied()
                .filter(|idx| new_cells.binary_search(idx).is_err())
                .collect();
            self.mark_gel(take.iter().chain(&give).copied());
            self.mark_gel(remapped.iter().flatten().map(|(idx, _)| *idx));
            // cells grown over leave the gel with their gas
            for &idx in &take {
                for f in self.fields.iter_mut() {
                    self.displaced_gas -= f[idx] * h3;
                    f[idx] = 0.0;
                }
            }
            self.grid.set_excluded(&take, true);
            self.grid.set_excluded(&give, false);
            for (idx, values) in remapped.iter().flatten() {
                if !self.grid.inside(*idx) {
                    continue;
                }
                for (f, v) in self.fields.iter_mut().zip(values) {
                    self.displaced_gas += (v - f[*idx]) * h3;
                    f[*idx] = *v;
                }
            }
            if remapped.iter().all(|p| p.is_empty()) && !give.is_empty() {
                // no remap: the cells given back take the gel next to them, outer cells first
                let mut order = give.clone();
                let dist = |idx: usize| {
                    let [nx, ny, _] = self.grid.n;
                    let p = [idx % nx, (idx / nx) % ny, idx / (nx * ny)];
                    (0..3)
                        .map(|a| ((p[a] as f64 + 0.5) * h - centre[a]).powi(2))
                        .sum::<f64>()
                };
                order.sort_by(|a, b| dist(*b).total_cmp(&dist(*a)));
                for idx in order {
                    for f in self.fields.iter_mut() {
                        let v = displacement::neighbour_mean(&self.grid, f, idx, 0.0);
                        self.displaced_gas += (v - f[idx]) * h3;
                        f[idx] = v;
                    }
                }
            }
            let mut cells = keep;
            cells.extend(take);
            cells.sort_unstable();
            let st = &mut self.displaced[i];
            st.cells = cells;
            st.radius = r_new;
            st.centre = centre;
        }
    }

    pub(super) fn coalesce(
        &mut self,
        t: f64,
        p: f64,
        events: &mut Vec<Event>,
    ) -> Result<(), Error> {
        loop {
            let mut pair = None;
            'outer: for i in 0..self.bubbles.len() {
                if !self.bubbles[i].active() {
                    continue;
                }
                for j in i + 1..self.bubbles.len() {
                    if !self.bubbles[j].active() {
                        continue;
                    }
                    let (a, b) = (&self.bubbles[i], &self.bubbles[j]);
                    let d2: f64 = (0..3)
                        .map(|k| (a.position[k] - b.position[k]).powi(2))
                        .sum();
                    if d2.sqrt() <= a.radius + b.radius {
                        pair = Some((i, j));
                        break 'outer;
                    }
                }
            }
            let Some((i, j)) = pair else { return Ok(()) };
            // the bubble with more gas survives; centre weighted by gas content
            let (keep, gone) = if self.bubbles[i].total_moles() >= self.bubbles[j].total_moles() {
                (i, j)
            } else {
                (j, i)
            };
            let nk = self.bubbles[keep].total_moles();
            let ng = self.bubbles[gone].total_moles();
            let mut pos = [0.0; 3];
            for (k, c) in pos.iter_mut().enumerate() {
                *c = (self.bubbles[keep].position[k] * nk + self.bubbles[gone].position[k] * ng)
                    / (nk + ng);
            }
            let gone_moles = self.bubbles[gone].moles.clone();
            let r0 = (self.bubbles[keep].initial_radius.powi(3)
                + self.bubbles[gone].initial_radius.powi(3))
            .cbrt();
            {
                let b = &mut self.bubbles[keep];
                b.position = pos;
                b.initial_radius = r0;
                for (m, x) in b.moles.iter_mut().zip(&gone_moles) {
                    *m += x;
                }
            }
            self.bubbles[gone].fate = BubbleFate::Merged {
                into: keep,
                time: t,
            };
            self.bubbles[gone].moles.iter_mut().for_each(|m| *m = 0.0);
            self.bubbles[gone].radius = 0.0;
            let nrt = self.bubbles[keep].total_moles() * self.rt;
            let guess = self.bubbles[keep].radius;
            let r = self
                .balance_for(&self.bubbles[keep], p)
                .radius_for(nrt, guess)
                .ok_or_else(|| Error::Solver(format!("merged bubble {keep}: no Laplace radius")))?;
            self.bubbles[keep].radius = r;
            events.push(Event::Coalesced {
                time: t,
                into: keep,
                absorbed: gone,
            });
        }
    }

    /// The nucleation model's nuclei in this grid, as a pool ([`Self::new`]).
    pub(super) fn nucleus_pool(&self) -> Result<NucleusPool, Error> {
        let input =
            |field: &str, m: String| Error::Input(crate::error::InputError::new(m).field(field));
        let nuclei = self
            .params
            .nucleation
            .nuclei(&self.grid)
            .map_err(|e| input(&e.field, e.message))?;
        NucleusPool::new(
            &nuclei,
            &self.grid,
            self.params.surface_tension,
            self.params.nucleation.skin_compression(),
        )
        .map_err(|e| input(&e.field, e.message))
    }

    /// An upper bound of the gel tension (Σ_g C_g·R_u·T/L_g + p_fixed) anywhere in the gel up to
    /// `t1`, Pa, kept up to date over the step from `t0`: by the discrete maximum principle of
    /// both diffusion schemes (tested in `diffusion`) the gel's tension never exceeds the
    /// largest of its initial value, the open faces' and the perfusion's value (the inspired
    /// inert gas plus p_fixed, at the step's ends and the profile's breakpoints in it) and the
    /// bubbles' gas pressure (Σ n·R_u·T/V + p_fixed), the sources the exchange draws from.
    /// [`Self::nucleate`] skips the nuclei while it stays 10 % below their lowest threshold
    /// (the margin covers a bubble's pressure changing within a step).
    pub(super) fn tension_bound(&mut self, profile: &PressureHistory, t0: f64, t1: f64) -> f64 {
        let fixed = self.params.bubble_fixed_gases;
        let mut b = match self.tension_bound {
            Some(b) => b,
            None => {
                let k: Vec<f64> = self.ostwald.iter().map(|l| self.rt / l).collect();
                let fields = self.field_views();
                (0..self.grid.len())
                    .filter(|&c| self.grid.inside(c))
                    .map(|c| fields.iter().zip(&k).map(|(f, kg)| f[c] * kg).sum::<f64>())
                    .fold(0.0, f64::max)
                    + fixed
            }
        };
        // the open faces' value at `t` with the gas of segment `seg`
        let inspired = |seg: usize, t: f64| -> f64 {
            self.gases
                .iter()
                .map(|g| profile.inspired_partial_pressure_on(*g, seg, t))
                .sum::<f64>()
                + fixed
        };
        // the step's segment at both ends (the faces of a step that ends on a gas switch keep
        // the old gas to its end), and at a breakpoint inside it the gases on both sides
        let seg = profile.step_segment(t0, t1);
        b = b.max(inspired(seg, t0)).max(inspired(seg, t1));
        let first = profile.times_s.partition_point(|&x| x <= t0);
        for &tb in profile.times_s[first..].iter().take_while(|&&x| x < t1) {
            let after = profile.segment(tb);
            b = b
                .max(inspired(after, tb))
                .max(inspired(after.saturating_sub(1), tb));
        }
        let ng = self.gases.len();
        for bubble in self.bubbles.iter().filter(|x| x.active()) {
            let n: f64 = bubble.moles[..ng].iter().sum();
            b = b.max(n * self.rt / bubble.volume() + fixed);
        }
        self.tension_bound = Some(b);
        b
    }

    /// The nuclei of the run and their state (empty under the `fixed` model).
    pub fn nuclei(&self) -> &NucleusPool {
        &self.nuclei
    }

    /// Phase 8: nucleation ([`crate::phantom::nucleation`]).
    /// 1. A nucleated bubble that has shrunk below a tenth of its nucleus radius has dissolved:
    ///    its gas returns to the gel (the step limits of [`Self::choose_step`] are sized for
    ///    bubbles of many µm; a sub-µm bubble left to shrink further would leave the range of the
    ///    radius solve).
    /// 2. Nuclei whose bubble has dissolved return to the pool (one whose bubble merged into
    ///    another is consumed: its gas is in the survivor).
    /// 3. Every nucleus in the pool whose cell's supersaturation
    ///    Σ_g C_g·R_u·T/L_g + p_fixed − P_amb exceeds its 2γ/r (eq. 2.11), and for which the
    ///    gel tension that its bubble would see (the coupling sphere of a bubble of radius r,
    ///    as in [`Self::fluxes`]) exceeds P_amb + 2γ/r too, becomes a bubble of its radius
    ///    ([`Self::add_bubble`]), unless it touches an active bubble (it would merge into it at
    ///    the next step, and its nucleus return to the pool, for ever). The cell value is the
    ///    cheap test of every nucleus; the coupling sphere is read only for those that pass it,
    ///    so that a new bubble starts growing (without it, a nucleus at a peak of the field
    ///    activates, sees a lower mean tension at its coupling sphere, dissolves, and activates
    ///    again at the next step). In a uniform gel both are the same number.
    ///
    /// `tensions` and `fluxes` (the time loop's per-bubble buffers) grow with the bubbles.
    pub(super) fn nucleate(
        &mut self,
        profile: &PressureHistory,
        t0: f64,
        p1: f64,
        tensions: &mut Vec<f64>,
        fluxes: &mut Vec<Vec<f64>>,
        events: &mut Vec<Event>,
    ) -> Result<(), Error> {
        if self.nuclei.is_empty() {
            return Ok(());
        }
        let mut pool = std::mem::take(&mut self.nuclei);
        let ng = self.gases.len();
        for e in pool.entries() {
            let Some(id) = e.bubble else { continue };
            let b = &self.bubbles[id];
            if b.active() && b.radius < 0.1 * e.nucleus.radius {
                let back: Vec<f64> = b.moles[..ng].iter().map(|m| -m).collect();
                self.take_from_grid(id, &back);
                self.dissolve(id, self.time, events);
            }
        }
        pool.release(|b| matches!(self.bubbles[b].fate, BubbleFate::Dissolved(_)));
        // no nucleus can activate while even the bound of the gel tension stays below the
        // lowest threshold (bare nuclei only: with skins every step records the crushing)
        if !pool.has_skins() {
            let bound = self.tension_bound(profile, t0, self.time);
            if bound - p1 < 0.9 * pool.lowest_threshold() {
                self.nuclei = pool;
                return Ok(());
            }
        }
        let k: Vec<f64> = self.ostwald.iter().map(|l| self.rt / l).collect();
        let fixed = self.params.bubble_fixed_gases;
        let ready = pool.ready(|cell| {
            let mut tension = fixed;
            for (f, kg) in self.fields.iter().zip(&k) {
                tension += f[cell] * kg;
            }
            tension - p1
        });
        // the coupling-sphere test of every candidate first, on the gel of the end of the
        // step (the gas each new bubble takes must not decide for its neighbours)
        let mut confirmed = Vec::with_capacity(ready.len());
        for index in ready {
            let e = pool.entries()[index];
            let threshold = pool.threshold(index);
            let rho = self.coupling_radius_at(pool.activation_radius(index), false);
            let ng = k.len();
            let (mut here, mut mean) = ([0.0; Gas::ALL.len()], [0.0; Gas::ALL.len()]);
            for (h, f) in here.iter_mut().zip(self.fields.iter()) {
                *h = f[e.cell];
            }
            self.prepare_sphere_at(rho);
            self.sphere_means(e.nucleus.position, rho, &here[..ng], &mut mean[..ng]);
            let mut tension = fixed;
            for (m, kg) in mean.iter().zip(&k) {
                tension += m * kg;
            }
            if tension - p1 > threshold {
                confirmed.push(index);
            }
        }
        let mut result = Ok(());
        for index in confirmed {
            let n = Nucleus {
                radius: pool.activation_radius(index),
                ..pool.entries()[index].nucleus
            };
            let engulfed = self.bubbles.iter().any(|b| {
                b.active()
                    && (0..3)
                        .map(|a| (b.position[a] - n.position[a]).powi(2))
                        .sum::<f64>()
                        < (b.radius + n.radius).powi(2)
            });
            if engulfed {
                continue;
            }
            match self.add_bubble(n.position, n.radius, p1) {
                Ok(Some(id)) => pool.activate(index, id),
                Ok(None) => {}
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        self.nuclei = pool;
        tensions.resize(self.bubbles.len(), 0.0);
        fluxes.resize(self.bubbles.len(), vec![0.0; self.gases.len()]);
        result
    }

    /// Add a bubble of radius `r` (m) centred at `position` (m) at the current time: at Laplace
    /// equilibrium (eq. 2.4) at ambient `ambient` (Pa), R0 = r and P0 = `ambient` for the
    /// elasticity and surface laws, with the composition of the gel's gas tension in its cell.
    /// Its gas is taken from the gel through its sink kernel, so the total is conserved.
    /// Returns its id, or `None` when the gel there holds no gas to give (nothing is added).
    pub fn add_bubble(
        &mut self,
        position: [f64; 3],
        r: f64,
        ambient: f64,
    ) -> Result<Option<usize>, Error> {
        let cell = crate::phantom::nucleation::cell_of(&self.grid, position)
            .filter(|c| self.grid.inside(*c))
            .ok_or_else(|| {
                Error::Solver(format!(
                    "a bubble added at ({:.3e}, {:.3e}, {:.3e}) m is outside the phantom",
                    position[0], position[1], position[2]
                ))
            })?;
        let ng = self.gases.len();
        let partial: Vec<f64> = (0..ng)
            .map(|g| self.fields[g][cell].max(0.0) * self.rt / self.ostwald[g])
            .collect();
        let psum: f64 = partial.iter().sum();
        if !(psum > 0.0) {
            return Ok(None);
        }
        let id = self.bubbles.len();
        let mut bubble = Bubble {
            id,
            position,
            initial_radius: r,
            initial_ambient: ambient,
            moles: vec![0.0; ng],
            radius: r,
            fate: BubbleFate::Active,
        };
        let n_total = self.balance_for(&bubble, ambient).pv(r) / self.rt;
        if !(n_total > 0.0 && n_total.is_finite()) {
            return Err(Error::Input(
                crate::error::InputError::new(format!(
                    "a bubble of radius {r:.3e} m at P_amb = {ambient:.0} Pa holds no simulated gas at Laplace equilibrium (P_B ≤ material.bubble_fixed_gases_pa = {:.0} Pa)",
                    self.params.bubble_fixed_gases
                ))
                .field("material.bubble_fixed_gases_pa"),
            ));
        }
        self.bubbles.push(bubble.clone());
        let want: Vec<f64> = partial.iter().map(|p| n_total * p / psum).collect();
        let taken = self.take_from_grid(id, &want);
        bubble.moles.copy_from_slice(&taken[..ng]);
        let nrt = bubble.total_moles() * self.rt;
        let radius = if nrt > 0.0 {
            self.balance_for(&bubble, ambient).radius_for(nrt, r)
        } else {
            None
        };
        match radius {
            Some(radius) => {
                bubble.radius = radius;
                self.bubbles[id] = bubble;
                Ok(Some(id))
            }
            None => {
                // nothing the Laplace balance can hold: give the gas back, add nothing
                let back: Vec<f64> = taken[..ng].iter().map(|m| -m).collect();
                self.take_from_grid(id, &back);
                self.bubbles.pop();
                Ok(None)
            }
        }
    }
}
