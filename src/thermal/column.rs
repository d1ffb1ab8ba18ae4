//! Heat conduction through the thickness of one ply (docs/model.md Eqs. (H3), (H4)).
//!
//! The blank is a thin shell: heat crosses a ply's thickness (0.3 mm) in a fraction of a
//! second but its width in minutes, so each node of the shell carries its own 1D column of
//! finite volumes through the thickness, stepped implicitly, while in-plane conduction (slow,
//! explicit) reaches the column as a source per cell. The column sees the current geometry:
//! the layers thin out and the ply stretches while it is formed, and both change how fast heat
//! crosses it.

use std::ops::Range;

/// One layer of the stack, bottom face first: its reference thickness (mm) and its
/// conductivity through the thickness (N/(s K), numerically W/(m K)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColumnLayer {
    pub thickness: f64,
    pub conductivity: f64,
}

/// The finite volumes of a column: every layer cut into the same number of equal cells, so
/// that a cell never straddles two conductivities and a layer's mean is a plain mean.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnGrid {
    layers: Vec<ColumnLayer>,
    cells_per_layer: usize,
}

impl ColumnGrid {
    /// Cuts `layers` (bottom face first) into `cells_per_layer` cells each, or says what is
    /// wrong with them.
    pub fn new(layers: &[ColumnLayer], cells_per_layer: usize) -> Result<Self, String> {
        if layers.is_empty() {
            return Err("a through-thickness column needs at least one layer".into());
        }
        if cells_per_layer == 0 {
            return Err("a through-thickness column needs at least one cell per layer".into());
        }
        for (i, layer) in layers.iter().enumerate() {
            check_positive(layer.thickness, "thickness (mm)", i)?;
            check_positive(layer.conductivity, "through-thickness conductivity", i)?;
        }
        Ok(Self {
            layers: layers.to_vec(),
            cells_per_layer,
        })
    }

    /// Number of cells, bottom face first.
    pub fn cells(&self) -> usize {
        self.layers.len() * self.cells_per_layer
    }

    pub fn layers(&self) -> &[ColumnLayer] {
        &self.layers
    }

    /// The layer that holds `cell`.
    pub fn layer_of(&self, cell: usize) -> usize {
        cell / self.cells_per_layer
    }

    /// Reference thickness of `cell` (mm).
    pub fn cell_thickness(&self, cell: usize) -> f64 {
        self.layers[self.layer_of(cell)].thickness / self.cells_per_layer as f64
    }

    /// The cells of `layer`.
    pub fn cell_range(&self, layer: usize) -> Range<usize> {
        layer * self.cells_per_layer..(layer + 1) * self.cells_per_layer
    }

    /// Mean temperature of each layer into `out` (one per layer). The cells of a layer are of
    /// equal thickness, in the reference and (one `lambda3` per layer) in the current
    /// geometry, so the thickness-weighted mean is the plain mean of its cells.
    pub fn layer_means(&self, temps: &[f64], out: &mut [f64]) {
        assert_eq!(temps.len(), self.cells(), "one temperature per cell");
        assert_eq!(out.len(), self.layers.len(), "one mean per layer");
        for (layer, mean) in out.iter_mut().enumerate() {
            let cells = &temps[self.cell_range(layer)];
            *mean = cells.iter().sum::<f64>() / cells.len() as f64;
        }
    }

    fn conductivity(&self, cell: usize) -> f64 {
        self.layers[self.layer_of(cell)].conductivity
    }

    /// Half the thermal resistance of `cell` across its current thickness, per unit area:
    /// `dz / (2 k)` of docs/model.md Eq. (H3), `dz = dz_ref lambda3`.
    fn half_resistance(&self, cell: usize, thickness_stretch: &[f64]) -> f64 {
        let dz = self.cell_thickness(cell) * thickness_stretch[self.layer_of(cell)];
        dz / (2.0 * self.conductivity(cell))
    }
}

fn check_positive(value: f64, quantity: &str, layer: usize) -> Result<(), String> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "the {quantity} of layer #{} of the column must be positive and finite, not {value}",
            layer + 1
        ))
    }
}

/// What a face of the column exchanges heat with: a heat-transfer coefficient `h`
/// (N/(mm s K), 1e-3 x W/(m^2 K)) to an outside temperature (°C), docs/model.md Eq. (H4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceExchange {
    pub conductance: f64,
    pub temperature: f64,
}

impl FaceExchange {
    /// A face that exchanges nothing (h = 0); its outside temperature is never used.
    pub fn insulated() -> Self {
        Self {
            conductance: 0.0,
            temperature: 0.0,
        }
    }

    /// `U = 1 / (1/h + dz/(2k))`, docs/model.md Eq. (H4): the face's coefficient in series
    /// with the half cell next to it, so that `U (T_cell - T_out)` is the heat flux through the
    /// face. Zero for an insulated face (no division by h = 0).
    fn coefficient(&self, half_resistance: f64) -> f64 {
        if self.conductance > 0.0 {
            1.0 / (1.0 / self.conductance + half_resistance)
        } else {
            0.0
        }
    }
}

/// One time step of a column: everything but the grid and the temperatures.
#[derive(Clone, Copy, Debug)]
pub struct ColumnStep<'a> {
    /// Per cell, `rho c dz_ref` (N/(mm K)): heat per unit reference area per kelvin. The heat
    /// a cell holds does not change when it is stretched, so this is a reference quantity.
    pub capacities: &'a [f64],
    /// Per layer, `lambda3`: current over reference thickness.
    pub thickness_stretch: &'a [f64],
    /// Current over reference area of the column (the in-plane stretch `J2`).
    pub area_ratio: f64,
    /// Bottom and top face.
    pub faces: [FaceExchange; 2],
    /// Per cell, heat added over the step per unit reference area (N/mm), e.g. in-plane
    /// conduction computed explicitly by the caller, or latent heat (docs/model.md Eq. (H8)).
    pub sources: &'a [f64],
    /// Duration of the step (s).
    pub dt: f64,
}

/// Work vectors of [`step_column`], kept between calls so that a step allocates nothing once
/// the scratch has grown to the column's size.
#[derive(Clone, Debug, Default)]
pub struct ColumnScratch {
    /// `links[i]`: conductance between cells `i` and `i + 1` per unit reference area.
    links: Vec<f64>,
    /// Diagonal of the system, then the pivots of the elimination.
    diagonal: Vec<f64>,
    /// Right-hand side, then the forward-eliminated right-hand side, then the increment.
    rhs: Vec<f64>,
    /// Upper diagonal divided by the pivot (Thomas algorithm).
    upper: Vec<f64>,
}

/// Advances `temps` (°C, one per cell) by one backward-Euler step and returns the heat that
/// left through the bottom and top face over the step, per unit reference area (N/mm).
///
/// The system is solved for the increment (delta form):
/// `(C + dt (K + H)) dT = -dt (K T + H (T - T_out)) + sources`, with `K` the conductances of
/// docs/model.md Eq. (H3) and `H` the face coefficients of Eq. (H4), both in the current
/// geometry and times `area_ratio`. The right-hand side is built from temperature
/// differences only, so a column that starts at its outside temperatures with no sources has
/// a right-hand side of exactly 0.0 and keeps its temperatures to the bit, however long it is
/// stepped. The heat out is `dt U (T_face_new - T_out)`, the same flux the solve used, so
/// `sum C (T_new - T_old) = sum sources - (out[0] + out[1])` to round-off.
///
/// The caller hands positive capacities, stretches, area ratio and step (they come from the
/// solver, not from the user, and are not checked); slices of the wrong length panic.
pub fn step_column(
    grid: &ColumnGrid,
    step: &ColumnStep,
    temps: &mut [f64],
    scratch: &mut ColumnScratch,
) -> [f64; 2] {
    let n = grid.cells();
    assert_eq!(temps.len(), n, "one temperature per cell");
    assert_eq!(step.capacities.len(), n, "one capacity per cell");
    assert_eq!(step.sources.len(), n, "one source per cell");
    assert_eq!(
        step.thickness_stretch.len(),
        grid.layers().len(),
        "one thickness stretch per layer"
    );
    let [bottom, top] = face_coefficients(grid, step);
    assemble(grid, step, temps, [bottom, top], scratch);
    solve_tridiagonal(scratch, step.dt);
    for (t, d) in temps.iter_mut().zip(&scratch.rhs) {
        *t += d;
    }
    [
        step.dt * bottom * (temps[0] - step.faces[0].temperature),
        step.dt * top * (temps[n - 1] - step.faces[1].temperature),
    ]
}

/// The face coefficients `U` of docs/model.md Eq. (H4) per unit reference area.
fn face_coefficients(grid: &ColumnGrid, step: &ColumnStep) -> [f64; 2] {
    let last = grid.cells() - 1;
    let bottom = step.faces[0].coefficient(grid.half_resistance(0, step.thickness_stretch));
    let top = step.faces[1].coefficient(grid.half_resistance(last, step.thickness_stretch));
    [step.area_ratio * bottom, step.area_ratio * top]
}

/// Fills the scratch with the links, the diagonal and the right-hand side of the delta form.
fn assemble(
    grid: &ColumnGrid,
    step: &ColumnStep,
    temps: &[f64],
    [bottom, top]: [f64; 2],
    scratch: &mut ColumnScratch,
) {
    let n = grid.cells();
    let dt = step.dt;
    scratch.links.clear();
    scratch.links.extend((0..n - 1).map(|i| {
        let resistance = grid.half_resistance(i, step.thickness_stretch)
            + grid.half_resistance(i + 1, step.thickness_stretch);
        step.area_ratio / resistance
    }));
    scratch.diagonal.clear();
    scratch.rhs.clear();
    for i in 0..n {
        let mut diagonal = step.capacities[i];
        let mut outflow = 0.0;
        if i > 0 {
            let g = scratch.links[i - 1];
            diagonal += dt * g;
            outflow += g * (temps[i] - temps[i - 1]);
        }
        if i + 1 < n {
            let g = scratch.links[i];
            diagonal += dt * g;
            outflow += g * (temps[i] - temps[i + 1]);
        }
        if i == 0 {
            diagonal += dt * bottom;
            outflow += bottom * (temps[0] - step.faces[0].temperature);
        }
        if i == n - 1 {
            diagonal += dt * top;
            outflow += top * (temps[n - 1] - step.faces[1].temperature);
        }
        scratch.diagonal.push(diagonal);
        scratch.rhs.push(step.sources[i] - dt * outflow);
    }
}

/// Thomas algorithm on the symmetric tridiagonal system in the scratch, whose off-diagonal
/// is `-dt links`: leaves the increment in `scratch.rhs`. No pivoting is needed: with positive
/// capacities the matrix is strictly diagonally dominant.
fn solve_tridiagonal(scratch: &mut ColumnScratch, dt: f64) {
    let n = scratch.diagonal.len();
    let ColumnScratch {
        links,
        diagonal,
        rhs,
        upper,
    } = scratch;
    upper.clear();
    upper.resize(n, 0.0);
    let mut pivot = diagonal[0];
    for i in 0..n {
        if i > 0 {
            let coupling = dt * links[i - 1];
            pivot = diagonal[i] - coupling * upper[i - 1];
            rhs[i] += coupling * rhs[i - 1];
        }
        rhs[i] /= pivot;
        if i + 1 < n {
            upper[i] = dt * links[i] / pivot;
        }
    }
    for i in (0..n - 1).rev() {
        rhs[i] += upper[i] * rhs[i + 1];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One T300/PPS ply as A:B:A, 0.04 : 0.23 : 0.04 mm (materials/t300-5hs-pps.toml).
    const SKIN: f64 = 0.04;
    const CORE: f64 = 0.23;
    const PLY: f64 = SKIN + CORE + SKIN;
    /// Volumetric heat capacity, N/(mm^2 K) (= MJ/(m^3 K)).
    const RHO_C: f64 = 1.872;
    /// Conductivity through the thickness, N/(s K) (= W/(m K)).
    const K: f64 = 0.3;

    fn ply_grid(conductivities: [f64; 3], cells_per_layer: usize) -> ColumnGrid {
        let layers: Vec<ColumnLayer> = [SKIN, CORE, SKIN]
            .iter()
            .zip(conductivities)
            .map(|(&thickness, conductivity)| ColumnLayer {
                thickness,
                conductivity,
            })
            .collect();
        ColumnGrid::new(&layers, cells_per_layer).unwrap()
    }

    fn capacities(grid: &ColumnGrid) -> Vec<f64> {
        (0..grid.cells())
            .map(|c| RHO_C * grid.cell_thickness(c))
            .collect()
    }

    /// Centre of every cell in the current geometry, measured from the bottom face (mm).
    fn cell_centres(grid: &ColumnGrid, stretch: &[f64]) -> Vec<f64> {
        let mut bottom = 0.0;
        (0..grid.cells())
            .map(|c| {
                let dz = grid.cell_thickness(c) * stretch[grid.layer_of(c)];
                bottom += dz;
                bottom - 0.5 * dz
            })
            .collect()
    }

    /// The `count` first roots of `zeta tan zeta = bi`, one in each
    /// `[(n-1) pi, (n-1) pi + pi/2]`, by bisection on `zeta sin zeta - bi cos zeta`.
    fn eigenvalues(bi: f64, count: usize) -> Vec<f64> {
        let g = |z: f64| z * z.sin() - bi * z.cos();
        (0..count)
            .map(|n| {
                let (mut lo, mut hi) = (n as f64 * std::f64::consts::PI, 0.0);
                hi += lo + std::f64::consts::FRAC_PI_2;
                let g_lo = g(lo);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if (g(mid) < 0.0) == (g_lo < 0.0) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                0.5 * (lo + hi)
            })
            .collect()
    }

    /// Classic series solution of a slab of thickness `l`, insulated at x = 0 and cooled by
    /// `h` at x = l: `theta/theta0 = sum C_n exp(-zeta_n^2 Fo) cos(zeta_n x/l)`,
    /// `C_n = 4 sin zeta_n / (2 zeta_n + sin 2 zeta_n)` (Incropera, Eq. 5.42).
    fn series(zetas: &[f64], fo: f64, x_over_l: f64) -> f64 {
        zetas
            .iter()
            .map(|&z| {
                let c = 4.0 * z.sin() / (2.0 * z + (2.0 * z).sin());
                c * (-z * z * fo).exp() * (z * x_over_l).cos()
            })
            .sum()
    }

    /// Largest error, over the times and over the insulated face, the centre, the cooled face
    /// and every cell centre, of the column against the series solution, as a fraction of
    /// `T0 - T_out`.
    fn slab_error(bi: f64, cells_per_layer: usize, dt: f64) -> f64 {
        let (t0, t_out) = (300.0, 20.0);
        let h = bi * K / PLY;
        let grid = ply_grid([K; 3], cells_per_layer);
        let n = grid.cells();
        let caps = capacities(&grid);
        let sources = vec![0.0; n];
        let stretch = [1.0; 3];
        let centres = cell_centres(&grid, &stretch);
        let step = ColumnStep {
            capacities: &caps,
            thickness_stretch: &stretch,
            area_ratio: 1.0,
            faces: [
                FaceExchange::insulated(),
                FaceExchange {
                    conductance: h,
                    temperature: t_out,
                },
            ],
            sources: &sources,
            dt,
        };
        let zetas = eigenvalues(bi, 60);
        let alpha = K / RHO_C;
        let mut temps = vec![t0; n];
        let mut scratch = ColumnScratch::default();
        let mut time = 0.0;
        let mut worst: f64 = 0.0;
        for check in [0.05, 0.1, 0.3, 0.6, 1.2] {
            while time < check - 0.5 * dt {
                step_column(&grid, &step, &mut temps, &mut scratch);
                time += dt;
            }
            let fo = alpha * time / (PLY * PLY);
            let exact = |x: f64| t_out + (t0 - t_out) * series(&zetas, fo, x / PLY);
            // The cooled face from flux continuity, h (T_s - T_out) = U (T_cell - T_out).
            let half = grid.cell_thickness(n - 1) / (2.0 * K);
            let face = t_out + (temps[n - 1] - t_out) / (1.0 + h * half);
            // Three layers: the centre is that of the middle cell (odd count) or between two.
            let centre = if n % 2 == 1 {
                temps[n / 2]
            } else {
                0.5 * (temps[n / 2 - 1] + temps[n / 2])
            };
            let mut points = vec![(temps[0], 0.0), (centre, 0.5 * PLY), (face, PLY)];
            points.extend(temps.iter().copied().zip(centres.iter().copied()));
            for (t, x) in points {
                worst = worst.max((t - exact(x)).abs() / (t0 - t_out));
            }
        }
        worst
    }

    /// Biot 0.4 and 1 (h = 0.387 and 0.968 N/(mm s K)): within 1 % of `T0 - T_out` with
    /// 8 cells per layer and dt = 1e-3 s (measured: see the report in the commit).
    #[test]
    fn slab_cooled_on_one_face_follows_the_series_solution() {
        for bi in [0.4, 1.0] {
            let error = slab_error(bi, 8, 1e-3);
            eprintln!("Biot {bi}: largest error {error:.2e} of T0 - T_out");
            assert!(error < 0.01, "Biot {bi}: error {error}");
        }
    }

    /// Halving the cells and quartering the step (backward Euler is first order in time, the
    /// finite volumes second order in space) should divide the error by 4; measured at
    /// Biot 1: 1.17e-2, 3.21e-3, 8.11e-4.
    #[test]
    fn slab_error_falls_with_finer_cells_and_steps() {
        let errors =
            [(2, 8e-3), (4, 2e-3), (8, 5e-4)].map(|(cells, dt)| slab_error(1.0, cells, dt));
        eprintln!("errors at Biot 1: {errors:?}");
        for pair in errors.windows(2) {
            assert!(pair[1] < pair[0] / 3.0, "{errors:?}");
        }
    }

    /// Both faces exposed to `h`: at a small Biot number the column cools as one lump,
    /// `T_out + (T0 - T_out) exp(-2 h t / (rho c t_ply))`.
    #[test]
    fn small_biot_column_cools_as_a_lump() {
        let (t0, t_out, h, dt) = (300.0, 20.0, 0.01, 0.01);
        let grid = ply_grid([K; 3], 4);
        let n = grid.cells();
        let caps = capacities(&grid);
        let sources = vec![0.0; n];
        let face = FaceExchange {
            conductance: h,
            temperature: t_out,
        };
        let step = ColumnStep {
            capacities: &caps,
            thickness_stretch: &[1.0; 3],
            area_ratio: 1.0,
            faces: [face; 2],
            sources: &sources,
            dt,
        };
        let mut temps = vec![t0; n];
        let mut scratch = ColumnScratch::default();
        let mut worst: f64 = 0.0;
        for i in 1..=3000 {
            step_column(&grid, &step, &mut temps, &mut scratch);
            let mean = mean_temperature(&caps, &temps);
            let lump = t_out + (t0 - t_out) * (-2.0 * h * i as f64 * dt / (RHO_C * PLY)).exp();
            worst = worst.max((mean - lump).abs() / (t0 - t_out));
        }
        eprintln!("lumped limit: largest error {worst:.2e} of T0 - T_out");
        assert!(worst < 0.01, "{worst}");
    }

    fn mean_temperature(caps: &[f64], temps: &[f64]) -> f64 {
        let heat: f64 = caps.iter().zip(temps).map(|(c, t)| c * t).sum();
        heat / caps.iter().sum::<f64>()
    }

    /// Layers of different conductivity between two fixed outside temperatures: the steady
    /// state is linear in each layer with the slopes of resistances in series, which the
    /// finite volumes of Eq. (H3) reproduce exactly, stretched layers included.
    #[test]
    fn steady_state_is_the_series_resistance_profile() {
        let conductivities = [0.25, 0.6, 0.4];
        let stretch = [0.9, 0.7, 1.0];
        let grid = ply_grid(conductivities, 5);
        let n = grid.cells();
        let caps = capacities(&grid);
        let sources = vec![0.0; n];
        let faces = [
            FaceExchange {
                conductance: 50.0,
                temperature: 300.0,
            },
            FaceExchange {
                conductance: 20.0,
                temperature: 40.0,
            },
        ];
        let step = ColumnStep {
            capacities: &caps,
            thickness_stretch: &stretch,
            area_ratio: 1.4,
            faces,
            sources: &sources,
            dt: 1e9,
        };
        let mut temps = vec![20.0; n];
        let mut scratch = ColumnScratch::default();
        for _ in 0..5 {
            step_column(&grid, &step, &mut temps, &mut scratch);
        }
        // Resistances per unit current area, bottom face first.
        let thicknesses: Vec<f64> = [SKIN, CORE, SKIN]
            .iter()
            .zip(stretch)
            .map(|(t, s)| t * s)
            .collect();
        let layer_resistance: Vec<f64> = thicknesses
            .iter()
            .zip(conductivities)
            .map(|(t, k)| t / k)
            .collect();
        let total = 1.0 / 50.0 + layer_resistance.iter().sum::<f64>() + 1.0 / 20.0;
        let flux = (300.0 - 40.0) / total;
        let centres = cell_centres(&grid, &stretch);
        for (cell, (&t, &x)) in temps.iter().zip(&centres).enumerate() {
            let layer = grid.layer_of(cell);
            let below: f64 = thicknesses[..layer].iter().sum();
            let resistance = 1.0 / 50.0
                + layer_resistance[..layer].iter().sum::<f64>()
                + (x - below) / conductivities[layer];
            let exact = 300.0 - flux * resistance;
            assert!((t - exact).abs() < 1e-9, "cell {cell}: {t} vs {exact}");
        }
    }

    /// A column at its outside temperatures with no sources keeps every bit of its
    /// temperatures, stretched or not, however long it is stepped.
    #[test]
    fn isothermal_column_stays_isothermal_to_the_bit() {
        let t = 287.3;
        let grid = ply_grid([0.3, 0.45, 0.3], 6);
        let n = grid.cells();
        let caps = capacities(&grid);
        let sources = vec![0.0; n];
        let step = ColumnStep {
            capacities: &caps,
            thickness_stretch: &[0.8, 0.6, 0.8],
            area_ratio: 1.7,
            faces: [
                FaceExchange {
                    conductance: 0.5,
                    temperature: t,
                },
                FaceExchange {
                    conductance: 0.02,
                    temperature: t,
                },
            ],
            sources: &sources,
            dt: 0.013,
        };
        let mut temps = vec![t; n];
        let mut scratch = ColumnScratch::default();
        for _ in 0..1000 {
            let out = step_column(&grid, &step, &mut temps, &mut scratch);
            assert_eq!(out, [0.0, 0.0]);
        }
        assert!(
            temps.iter().all(|x| x.to_bits() == t.to_bits()),
            "{temps:?}"
        );
    }

    /// The heat a step stores equals the heat added less the heat out, to round-off.
    #[test]
    fn heat_balance_closes_to_round_off() {
        let grid = ply_grid([0.3, 0.5, 0.3], 5);
        let n = grid.cells();
        let caps = capacities(&grid);
        let sources: Vec<f64> = (0..n).map(|i| 0.01 * (i as f64 * 0.7).sin()).collect();
        let step = ColumnStep {
            capacities: &caps,
            thickness_stretch: &[0.9, 0.75, 0.9],
            area_ratio: 1.3,
            faces: [
                FaceExchange {
                    conductance: 0.8,
                    temperature: 60.0,
                },
                FaceExchange {
                    conductance: 0.03,
                    temperature: 25.0,
                },
            ],
            sources: &sources,
            dt: 0.02,
        };
        let mut temps: Vec<f64> = (0..n).map(|i| 280.0 + 15.0 * (i as f64).cos()).collect();
        let mut scratch = ColumnScratch::default();
        for _ in 0..50 {
            let old = temps.clone();
            let out = step_column(&grid, &step, &mut temps, &mut scratch);
            let stored: f64 = (0..n).map(|i| caps[i] * (temps[i] - old[i])).sum();
            let added: f64 = sources.iter().sum();
            let scale = stored.abs() + added.abs() + out[0].abs() + out[1].abs();
            let error = (stored - (added - out[0] - out[1])).abs() / scale;
            assert!(error < 1e-12, "relative imbalance {error}");
        }
    }

    fn relaxed(grid: &ColumnGrid, stretch: &[f64], area_ratio: f64, dt: f64) -> Vec<f64> {
        let n = grid.cells();
        // The same capacities for every grid: those of the ply's reference column.
        let caps = capacities(&ply_grid([K; 3], grid.cells() / 3));
        let sources = vec![0.0; n];
        let step = ColumnStep {
            capacities: &caps,
            thickness_stretch: stretch,
            area_ratio,
            faces: [
                FaceExchange::insulated(),
                FaceExchange {
                    conductance: 0.4,
                    temperature: 25.0,
                },
            ],
            sources: &sources,
            dt,
        };
        let mut temps: Vec<f64> = (0..n).map(|i| 200.0 + 5.0 * i as f64).collect();
        let mut scratch = ColumnScratch::default();
        for _ in 0..40 {
            step_column(grid, &step, &mut temps, &mut scratch);
        }
        temps
    }

    /// A column stretched to half its thickness holds the same heat but conducts it twice as
    /// fast through each cell: it is the column of half the reference thicknesses, and it
    /// relaxes in `dt` as far as the unstretched one in `2 dt` when its face is insulated.
    /// Doubling the area doubles every conductance, faces included: `2 dt` again.
    #[test]
    fn stretch_and_area_change_the_conductances() {
        let grid = ply_grid([K; 3], 4);
        let thin = ColumnGrid::new(
            &grid
                .layers()
                .iter()
                .map(|l| ColumnLayer {
                    thickness: 0.5 * l.thickness,
                    ..*l
                })
                .collect::<Vec<_>>(),
            4,
        )
        .unwrap();
        let stretched = relaxed(&grid, &[0.5; 3], 1.0, 0.01);
        let halved = relaxed(&thin, &[1.0; 3], 1.0, 0.01);
        let wider = relaxed(&grid, &[1.0; 3], 2.0, 0.01);
        let slower = relaxed(&grid, &[1.0; 3], 1.0, 0.02);
        for i in 0..grid.cells() {
            assert!((stretched[i] - halved[i]).abs() < 1e-12, "cell {i}");
            assert!((wider[i] - slower[i]).abs() < 1e-12, "cell {i}");
        }
        let plain = relaxed(&grid, &[1.0; 3], 1.0, 0.01);
        assert!(
            (plain[0] - slower[0]).abs() > 1.0,
            "the checks can tell the columns apart"
        );
    }

    #[test]
    fn grid_accessors_and_layer_means() {
        let grid = ply_grid([0.3, 0.5, 0.3], 2);
        assert_eq!(grid.cells(), 6);
        assert_eq!(grid.layer_of(3), 1);
        assert_eq!(grid.cell_range(2), 4..6);
        assert!((grid.cell_thickness(2) - 0.115).abs() < 1e-15);
        let mut means = [0.0; 3];
        grid.layer_means(&[1.0, 3.0, 5.0, 7.0, 9.0, 10.0], &mut means);
        assert_eq!(means, [2.0, 6.0, 9.5]);
    }

    #[test]
    fn rejects_malformed_columns() {
        let good = ColumnLayer {
            thickness: 0.1,
            conductivity: 0.3,
        };
        assert!(ColumnGrid::new(&[good], 0).unwrap_err().contains("cell"));
        assert!(ColumnGrid::new(&[], 2).is_err());
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let thin = ColumnLayer {
                thickness: bad,
                ..good
            };
            let e = ColumnGrid::new(&[good, thin], 2).unwrap_err();
            assert!(e.contains("thickness") && e.contains("#2"), "{e}");
            let insulating = ColumnLayer {
                conductivity: bad,
                ..good
            };
            let e = ColumnGrid::new(&[insulating], 2).unwrap_err();
            assert!(e.contains("conductivity"), "{e}");
        }
    }
}
