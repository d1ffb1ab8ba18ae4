//! The friction law between two plies: Coulomb friction plus the shear of the molten film
//! between them, capped at the film's yield (docs/model.md §6, "Friction through the molten
//! film", Eqs. (F1)–(F3)).
//!
//! The film of thickness `h_f` sheared at the slip speed `v` flows at the rate
//! `gamma_dot = v / h_f` and carries `tau_f = eta(gamma_dot) gamma_dot`; its viscosity is
//! constant (Newtonian), a power law with a lower cut-off rate (Eq. (F2)) or Cross's law
//! (Eq. (F3)). Every law is held as its viscosity at a vanishing rate over the thickness,
//! `eta_0 / h_f` (the field `film`), and the ratio `eta / eta_0` it falls to with the rate: the
//! Newtonian law is the ratio 1, so that it is exactly the law of a fixed viscosity.

/// How the film's viscosity falls with its shear rate `gamma_dot = v / h_f`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum FilmViscosity {
    /// `eta = eta_0` at every rate.
    #[default]
    Newtonian,
    /// Eq. (F2): `eta = K max(gamma_dot, gamma_c)^(n-1)`, so `eta_0 = K gamma_c^(n-1)`: a power
    /// law above the cut-off rate `gamma_c` (1/s), Newtonian below it (a pure power law's
    /// viscosity grows without bound as the plies stop).
    PowerLaw {
        /// `h_f` (mm), which turns the cut-off rate into a speed.
        thickness: f64,
        /// `n`, in (0, 1].
        index: f64,
        /// `gamma_c` (1/s).
        cutoff_rate: f64,
    },
    /// Eq. (F3): `eta = eta_0 / (1 + (eta_0 gamma_dot / tau_star)^(1-n))`: Newtonian at low
    /// rates, a power law of index `n` at high ones, turning over where the Newtonian stress
    /// reaches `tau_star` (MPa).
    Cross { index: f64, transition_stress: f64 },
}

impl FilmViscosity {
    /// `eta / eta_0` at slip `speed` (mm/s) for a film whose Newtonian stress at that speed is
    /// `newtonian_stress = (eta_0 / h_f) v` (MPa).
    fn ratio(&self, speed: f64, newtonian_stress: f64) -> f64 {
        match *self {
            Self::Newtonian => 1.0,
            Self::PowerLaw {
                thickness,
                index,
                cutoff_rate,
            } => {
                // the rate over the cut-off rate is the speed over the cut-off speed
                let cutoff_speed = thickness * cutoff_rate;
                (speed.max(cutoff_speed) / cutoff_speed).powf(index - 1.0)
            }
            Self::Cross {
                index,
                transition_stress,
            } => {
                // eta_0 gamma_dot = (eta_0 / h_f) v: the thickness drops out
                1.0 / (1.0 + (newtonian_stress / transition_stress).powf(1.0 - index))
            }
        }
    }

    /// The law that, at `factor` times the speed, carries what this one carries at the speed
    /// (with `eta_0` divided by `factor`, see [`FilmFriction::time_scaled`]).
    fn time_scaled(&self, factor: f64) -> Self {
        match *self {
            Self::PowerLaw {
                thickness,
                index,
                cutoff_rate,
            } => Self::PowerLaw {
                thickness,
                index,
                cutoff_rate: cutoff_rate * factor,
            },
            // Newtonian: nothing to scale; Cross: eta_0 gamma_dot / tau_star is unchanged when
            // eta_0 is divided by the factor the speed is multiplied by
            other => other,
        }
    }

    fn validate(&self) -> Result<(), String> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let (index, others): (f64, Vec<(&str, f64)>) = match *self {
            Self::Newtonian => return Ok(()),
            Self::PowerLaw {
                thickness,
                index,
                cutoff_rate,
            } => (
                index,
                vec![
                    ("film thickness", thickness),
                    ("cut-off shear rate", cutoff_rate),
                ],
            ),
            Self::Cross {
                index,
                transition_stress,
            } => (index, vec![("transition stress", transition_stress)]),
        };
        if !(index > 0.0 && index <= 1.0) {
            return Err(format!(
                "film power-law index {index} must lie above 0 and at most 1"
            ));
        }
        match others.iter().find(|(_, v)| !positive(*v)) {
            Some((what, v)) => Err(format!("{what} {v} must be > 0")),
            None => Ok(()),
        }
    }
}

/// The friction of an interface (model.md Eq. (F1)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmFriction {
    /// Coulomb coefficient `mu`.
    pub coulomb: f64,
    /// `eta_0 / h_f`, the film's viscosity at a vanishing shear rate over its thickness
    /// (MPa·s/mm = N·s/mm^3): for a Newtonian film its viscosity at every rate; 0: no film.
    pub film: f64,
    /// The film's yield shear stress `tau_max` (MPa); infinite: none.
    pub shear_cap: f64,
    /// How the viscosity falls with the film's shear rate.
    pub viscosity: FilmViscosity,
}

impl FilmFriction {
    /// Coulomb friction alone.
    pub fn coulomb(mu: f64) -> Self {
        Self::newtonian(mu, 0.0, f64::INFINITY)
    }

    /// Coulomb friction `mu`, a Newtonian film of `film = eta / h_f` (N·s/mm^3) and the cap
    /// `shear_cap` (MPa).
    pub fn newtonian(mu: f64, film: f64, shear_cap: f64) -> Self {
        Self {
            coulomb: mu,
            film,
            shear_cap,
            viscosity: FilmViscosity::Newtonian,
        }
    }

    /// Coulomb friction `mu` and a power-law film (Eq. (F2)) of consistency `consistency`
    /// (`K`, MPa·s^n), index `index`, cut-off rate `cutoff_rate` (1/s) and thickness
    /// `thickness` (mm), capped at `shear_cap` (MPa).
    pub fn power_law(
        mu: f64,
        (consistency, index, cutoff_rate): (f64, f64, f64),
        thickness: f64,
        shear_cap: f64,
    ) -> Self {
        let zero_rate_viscosity = consistency * cutoff_rate.powf(index - 1.0);
        Self {
            coulomb: mu,
            film: zero_rate_viscosity / thickness,
            shear_cap,
            viscosity: FilmViscosity::PowerLaw {
                thickness,
                index,
                cutoff_rate,
            },
        }
    }

    /// Coulomb friction `mu` and a Cross film (Eq. (F3)) of zero-rate viscosity
    /// `zero_rate_viscosity` (`eta_0`, MPa·s), index `index` and transition stress
    /// `transition_stress` (`tau_star`, MPa), `thickness` (mm) thick, capped at `shear_cap`
    /// (MPa).
    pub fn cross(
        mu: f64,
        (zero_rate_viscosity, index, transition_stress): (f64, f64, f64),
        thickness: f64,
        shear_cap: f64,
    ) -> Self {
        Self {
            coulomb: mu,
            film: zero_rate_viscosity / thickness,
            shear_cap,
            viscosity: FilmViscosity::Cross {
                index,
                transition_stress,
            },
        }
    }

    /// The largest tangential force a node of area `area` (mm^2) pressed with `normal_force`
    /// (N) carries while slipping at `speed` (mm/s) (N): Eq. (F1) over the node's area.
    pub fn slip_limit(&self, normal_force: f64, speed: f64, area: f64) -> f64 {
        let drag = self.coulomb * normal_force + self.film_stress(speed) * area;
        drag.min(self.shear_cap * area)
    }

    /// The film's shear stress `tau_f = eta(gamma_dot) v / h_f` at slip `speed` (mm/s) (MPa),
    /// before the cap: Eq. (F1)'s viscous term with Eq. (F2) or (F3).
    pub fn film_stress(&self, speed: f64) -> f64 {
        let newtonian = self.film * speed;
        newtonian * self.viscosity.ratio(speed, newtonian)
    }

    /// The law a solver running `factor` times faster than the process uses (docs/model.md §6,
    /// time scaling): at `factor` times the physical slip speed it carries the physical stress,
    /// as `eta1 / factor` does for the matrix. The Coulomb term and the cap do not depend on
    /// the speed.
    pub fn time_scaled(&self, factor: f64) -> Self {
        Self {
            film: self.film / factor,
            viscosity: self.viscosity.time_scaled(factor),
            ..*self
        }
    }

    /// Checks the values: finite, not negative, a positive cap, the thinning law's own.
    pub fn validate(&self) -> Result<(), String> {
        let fine = |v: f64| v.is_finite() && v >= 0.0;
        if !fine(self.coulomb) {
            return Err(format!(
                "friction coefficient {} must be >= 0",
                self.coulomb
            ));
        }
        if !fine(self.film) {
            return Err(format!(
                "film viscosity over thickness {} must be >= 0",
                self.film
            ));
        }
        if self.shear_cap.is_nan() || self.shear_cap <= 0.0 {
            return Err(format!("film yield stress {} must be > 0", self.shear_cap));
        }
        self.viscosity.validate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A PPS-like film at 300 °C (docs/model.md §6): eta_0 = 186 Pa·s, h_f = 10 µm.
    const ETA0: f64 = 186e-6;
    const H: f64 = 0.01;

    fn speeds() -> impl Iterator<Item = f64> {
        // 1e-4 to 1e4 mm/s, 20 a decade
        (0..=160).map(|i| 10f64.powf(-4.0 + i as f64 / 20.0))
    }

    fn laws() -> [FilmFriction; 3] {
        [
            FilmFriction::newtonian(0.2, ETA0 / H, 0.1),
            FilmFriction::power_law(0.2, (3.1e-3, 0.4, 1.0), H, 0.1),
            FilmFriction::cross(0.2, (ETA0, 0.4, 0.02), H, 0.1),
        ]
    }

    /// The Newtonian law is the fixed-viscosity law to the last bit.
    #[test]
    fn the_newtonian_law_is_the_fixed_viscosity_law() {
        let f = FilmFriction::newtonian(0.3, 2e-3, 0.05);
        for (n, v, a) in [(10.0f64, 0.0, 2.0), (3.0, 7.5, 1.25), (0.1, 1e3, 0.5)] {
            let fixed = (0.3 * n + 2e-3 * v * a).min(0.05 * a);
            assert_eq!(f.slip_limit(n, v, a), fixed);
        }
        assert_eq!(
            FilmFriction::coulomb(0.2).slip_limit(5.0, 1e6, 1.0),
            0.2 * 5.0
        );
    }

    /// Every law's stress grows with the speed, never falls, and has no jump: between two
    /// speeds 12 % apart it changes by at most the ratio of the speeds.
    #[test]
    fn the_stress_grows_with_the_speed_without_a_jump() {
        for law in laws() {
            let stresses: Vec<(f64, f64)> =
                speeds().map(|v| (v, law.slip_limit(1.0, v, 1.0))).collect();
            for w in stresses.windows(2) {
                let ((v0, t0), (v1, t1)) = (w[0], w[1]);
                assert!(t1 >= t0, "{law:?}: {t0} at {v0} mm/s, {t1} at {v1} mm/s");
                assert!(t1 <= t0 * v1 / v0 + 1e-15, "{law:?}: jumps at {v0} mm/s");
            }
        }
    }

    /// Cross's film is Newtonian (`eta_0 v / h`) well below the transition and a power law
    /// (`eta_0^n tau_star^(1-n) (v/h)^n`) well above it.
    #[test]
    fn cross_runs_from_newtonian_to_a_power_law() {
        let (eta0, n, tau_star) = (ETA0, 0.4, 0.02);
        let law = FilmFriction::cross(0.0, (eta0, n, tau_star), H, f64::INFINITY);
        // the transition is at eta_0 v / h = tau_star: v = 1.08 mm/s
        let slow = 1e-6;
        assert!((law.film_stress(slow) / (eta0 * slow / H) - 1.0).abs() < 1e-3);
        let fast = 1e7;
        let power = eta0.powf(n) * tau_star.powf(1.0 - n) * (fast / H).powf(n);
        assert!((law.film_stress(fast) / power - 1.0).abs() < 1e-3);
    }

    /// The power law's stress grows as `v^n` above the cut-off (its log-slope is n) and as `v`
    /// below it, equal to `K (v/h)^n` above.
    #[test]
    fn the_power_law_stress_grows_as_v_to_the_n() {
        let (k, n, cutoff) = (3.1e-3, 0.4, 1.0);
        let law = FilmFriction::power_law(0.0, (k, n, cutoff), H, f64::INFINITY);
        let slope =
            |v0: f64, v1: f64| (law.film_stress(v1) / law.film_stress(v0)).ln() / (v1 / v0).ln();
        // the cut-off speed is h gamma_c = 0.01 mm/s
        assert!((slope(1.0, 100.0) - n).abs() < 1e-9);
        assert!((slope(1e-5, 1e-3) - 1.0).abs() < 1e-9);
        assert!((law.film_stress(10.0) / (k * (10.0 / H).powf(n)) - 1.0).abs() < 1e-12);
    }

    /// A solver running 10 times faster sees, at 10 times the speed, the physical stress.
    #[test]
    fn a_time_scaled_law_carries_the_physical_stress_at_the_scaled_speed() {
        for law in laws() {
            let scaled = law.time_scaled(10.0);
            for v in [1e-3, 0.05, 1.0, 30.0, 500.0] {
                let (physical, run) = (
                    law.slip_limit(2.0, v, 1.5),
                    scaled.slip_limit(2.0, 10.0 * v, 1.5),
                );
                assert!((run / physical - 1.0).abs() < 1e-12, "{law:?} at {v}");
            }
        }
    }

    #[test]
    fn bad_thinning_parameters_are_refused() {
        assert!(FilmFriction::cross(0.2, (ETA0, 0.0, 0.02), H, 0.1)
            .validate()
            .is_err());
        assert!(FilmFriction::cross(0.2, (ETA0, 0.4, 0.0), H, 0.1)
            .validate()
            .is_err());
        assert!(FilmFriction::power_law(0.2, (1e-3, 1.5, 1.0), H, 0.1)
            .validate()
            .is_err());
        for law in laws() {
            assert!(law.validate().is_ok());
        }
    }
}
