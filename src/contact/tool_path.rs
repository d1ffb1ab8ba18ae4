//! A tool's path: a translation along a fixed direction by a travel that is a function of time
//! (docs/model.md §10, "Tool motions"), given as a table of displacements (the speed constant in
//! between) or of speeds (linear in between). Before its first time and after its last the tool
//! stands still.

use nalgebra::Vector3;

/// One piece of the travel: `s(t) = s0 + v0 (t - t0) + a (t - t0)^2 / 2` on `[t0, t1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Piece {
    t0: f64,
    t1: f64,
    s0: f64,
    v0: f64,
    a: f64,
}

impl Piece {
    fn travel(&self, t: f64) -> f64 {
        let tau = t.clamp(self.t0, self.t1) - self.t0;
        self.s0 + self.v0 * tau + 0.5 * self.a * tau * tau
    }
}

/// A translation along `direction` (unit) by a travel `s(t)` (mm).
#[derive(Clone, Debug, PartialEq)]
pub struct ToolPath {
    direction: Vector3<f64>,
    pieces: Vec<Piece>,
}

impl ToolPath {
    /// Through the points `(t, s)` of `table` (s, mm), at constant speed between them; the
    /// times rising, the first displacement 0 (a tool does not jump).
    pub fn from_displacements(direction: Vector3<f64>, table: &[[f64; 2]]) -> Result<Self, String> {
        check_table(table, "displacement")?;
        if table[0][1] != 0.0 {
            return Err(format!(
                "the displacement table starts at {} mm: a tool starts where it is placed, at 0",
                table[0][1]
            ));
        }
        let pieces = table
            .windows(2)
            .map(|w| Piece {
                t0: w[0][0],
                t1: w[1][0],
                s0: w[0][1],
                v0: (w[1][1] - w[0][1]) / (w[1][0] - w[0][0]),
                a: 0.0,
            })
            .collect();
        Self::along(direction, pieces)
    }

    /// With the speed linear between the points `(t, v)` of `table` (s, mm/s), from travel 0.
    pub fn from_speeds(direction: Vector3<f64>, table: &[[f64; 2]]) -> Result<Self, String> {
        check_table(table, "speed")?;
        let mut s0 = 0.0;
        let mut pieces = Vec::with_capacity(table.len() - 1);
        for w in table.windows(2) {
            let piece = Piece {
                t0: w[0][0],
                t1: w[1][0],
                s0,
                v0: w[0][1],
                a: (w[1][1] - w[0][1]) / (w[1][0] - w[0][0]),
            };
            s0 = piece.travel(piece.t1);
            pieces.push(piece);
        }
        Self::along(direction, pieces)
    }

    fn along(direction: Vector3<f64>, pieces: Vec<Piece>) -> Result<Self, String> {
        let length = direction.norm();
        if !(length.is_finite() && length > 0.0) {
            return Err("the direction must be a finite vector, not zero".into());
        }
        Ok(Self {
            direction: direction / length,
            pieces,
        })
    }

    /// The travel at `t` (mm).
    pub fn travel(&self, t: f64) -> f64 {
        match self.pieces.iter().find(|p| t <= p.t1) {
            Some(p) => p.travel(t),
            None => self.pieces.last().map_or(0.0, |p| p.travel(p.t1)),
        }
    }

    /// The translation at `t` (mm).
    pub fn displacement(&self, t: f64) -> Vector3<f64> {
        self.direction * self.travel(t)
    }

    /// The mean velocity over `[t - dt/2, t + dt/2]` (mm/s): what moves the tool by exactly the
    /// path's travel over a step centred on `t`.
    pub fn mean_velocity(&self, t: f64, dt: f64) -> Vector3<f64> {
        if dt <= 0.0 {
            return self.direction * self.speed(t);
        }
        (self.displacement(t + 0.5 * dt) - self.displacement(t - 0.5 * dt)) / dt
    }

    /// The speed at `t` (mm/s).
    pub fn speed(&self, t: f64) -> f64 {
        self.pieces
            .iter()
            .find(|p| t >= p.t0 && t < p.t1)
            .map_or(0.0, |p| p.v0 + p.a * (t - p.t0))
    }

    /// Unit direction of travel.
    pub fn direction(&self) -> Vector3<f64> {
        self.direction
    }

    /// The time its last point is reached (s).
    pub fn end_time(&self) -> f64 {
        self.pieces.last().map_or(0.0, |p| p.t1)
    }

    /// The largest speed along the path (mm/s).
    pub fn top_speed(&self) -> f64 {
        self.pieces
            .iter()
            .flat_map(|p| [p.v0.abs(), (p.v0 + p.a * (p.t1 - p.t0)).abs()])
            .fold(0.0, f64::max)
    }

    /// The time (s) at which the travel first reaches `s` (mm), if it does.
    pub fn time_to(&self, s: f64) -> Option<f64> {
        let p = self.pieces.iter().find(|p| p.travel(p.t1) >= s - 1e-12)?;
        let (mut lo, mut hi) = (p.t0, p.t1);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if p.travel(mid) < s {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(hi)
    }
}

/// At least two points, finite, times from 0 or later and strictly rising.
fn check_table(table: &[[f64; 2]], what: &str) -> Result<(), String> {
    if table.len() < 2 {
        return Err(format!(
            "the {what} table needs two points [time, {what}] at least"
        ));
    }
    if table.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!(
            "the {what} table holds a number that is not finite"
        ));
    }
    if table[0][0] < 0.0 {
        return Err(format!("the {what} table starts before time 0"));
    }
    if let Some(w) = table.windows(2).find(|w| w[1][0] <= w[0][0]) {
        return Err(format!(
            "the {what} table's times must rise: {} s follows {} s",
            w[1][0], w[0][0]
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_speed_table_integrates_to_its_area() {
        // trapezoid: 0 -> 10 mm/s in 1 s, 10 mm/s for 2 s, back to 0 in 1 s: 30 mm
        let path = ToolPath::from_speeds(
            Vector3::new(0.0, 0.0, 2.0),
            &[[0.0, 0.0], [1.0, 10.0], [3.0, 10.0], [4.0, 0.0]],
        )
        .unwrap();
        assert!((path.travel(1.0) - 5.0).abs() < 1e-12);
        assert!((path.travel(4.0) - 30.0).abs() < 1e-12);
        assert!((path.travel(9.0) - 30.0).abs() < 1e-12);
        assert!((path.displacement(4.0) - Vector3::new(0.0, 0.0, 30.0)).norm() < 1e-12);
        assert!((path.time_to(5.0).unwrap() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn steps_of_mean_velocity_add_up_to_the_travel() {
        let path = ToolPath::from_displacements(
            Vector3::x(),
            &[[0.0, 0.0], [0.3, 1.0], [1.0, 1.0], [2.0, 4.0]],
        )
        .unwrap();
        let (mut t, mut x) = (0.0, Vector3::zeros());
        let dt = 0.0137;
        while t < 2.5 {
            x += path.mean_velocity(t + 0.5 * dt, dt) * dt;
            t += dt;
        }
        assert!((x - path.displacement(t)).norm() < 1e-12, "{x:?}");
    }

    #[test]
    fn bad_tables_are_refused() {
        let d = Vector3::z();
        assert!(ToolPath::from_displacements(d, &[[0.0, 0.0]]).is_err());
        assert!(ToolPath::from_displacements(d, &[[0.0, 1.0], [1.0, 2.0]]).is_err());
        assert!(ToolPath::from_speeds(d, &[[0.0, 1.0], [0.0, 2.0]]).is_err());
        assert!(ToolPath::from_speeds(Vector3::zeros(), &[[0.0, 1.0], [1.0, 2.0]]).is_err());
    }
}
