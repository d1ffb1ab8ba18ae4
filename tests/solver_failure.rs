//! A run that goes wrong stops with a diagnosis and keeps what it recorded: a law whose wave
//! modulus is understated 400 times (so the time step is 20 times the critical one) blows up,
//! and the error names the step, the time, an element and the energies.

mod common;

use common::*;
use nalgebra::Vector3;
use std::sync::Arc;
use thermostamp::material::{
    Laminate, Layer, MaterialError, MaterialLaw, PointKinematics, ThicknessRule,
};
use thermostamp::mesh::{rectangle, DiagonalPattern};
use thermostamp::solver::{
    self, Constraint, Model, Motion, Observer, SolverError, SolverSettings, State,
};

/// The stiff-yarn fabric, but telling the solver its waves are 20 times slower than they are.
#[derive(Debug)]
struct Understated(Arc<dyn MaterialLaw>);

impl MaterialLaw for Understated {
    fn name(&self) -> &'static str {
        "understated fabric"
    }
    fn thickness_rule(&self) -> ThicknessRule {
        self.0.thickness_rule()
    }
    fn second_piola_kirchhoff(
        &self,
        point: &PointKinematics,
    ) -> Result<nalgebra::Matrix3<f64>, MaterialError> {
        self.0.second_piola_kirchhoff(point)
    }
    fn strain_energy(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        self.0.strain_energy(point)
    }
    fn wave_modulus(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        Ok(self.0.wave_modulus(point)? / 400.0)
    }
    fn time_scaled(&self, _speed_up: f64) -> Arc<dyn MaterialLaw> {
        Arc::new(Understated(self.0.clone()))
    }
}

#[derive(Default)]
struct Count(usize);

impl Observer for Count {
    fn record(&mut self, _: &Model, _: &State) -> anyhow::Result<()> {
        self.0 += 1;
        Ok(())
    }
}

#[test]
fn a_run_with_too_large_a_step_stops_with_a_diagnosis() {
    let card =
        thermostamp::material::MaterialCard::load(&repo_path("tests/data/stiff-yarn-fabric.toml"))
            .unwrap();
    let fabric = &card.laminate.layers()[0];
    let laminate = Laminate::new(vec![Layer {
        law: Arc::new(Understated(fabric.law.clone())),
        thickness: fabric.thickness,
    }])
    .unwrap();
    let mesh = rectangle(50.0, 100.0, 5, 10, DiagonalPattern::Crossed);
    let constraints = vec![
        Constraint {
            name: "bottom".into(),
            nodes: mesh.node_set("bottom").unwrap().to_vec(),
            motion: Motion::Fixed,
        },
        Constraint {
            name: "top".into(),
            nodes: mesh.node_set("top").unwrap().to_vec(),
            motion: Motion::Velocity(Arc::new(|_, _| Vector3::new(0.0, 10.0, 0.0))),
        },
    ];
    let elements = mesh.cells.len();
    let model = Model::new(
        mesh,
        laminate,
        card.density,
        20.0,
        Vector3::x(),
        constraints,
    )
    .unwrap();
    let settings = SolverSettings {
        end_time: 1.0,
        time_step_safety: 0.9,
        target_time_step: None,
        output_interval: 1e-3,
        damping: 0.0,
        yarn_damping: 0.0,
    };
    let mut count = Count::default();
    let err = solver::run(&model, &settings, &mut count).unwrap_err();
    let SolverError::Unstable {
        step,
        time,
        element,
        kinetic,
        ..
    } = &err
    else {
        panic!("expected an instability, got {err}");
    };
    assert!(*step > 0 && *time > 0.0 && *time < 1.0);
    assert!(*element < elements);
    assert!(
        kinetic.is_finite(),
        "energies are reported as numbers: {err}"
    );
    let message = err.to_string();
    for word in ["step", "element", "kinetic", "external"] {
        assert!(message.contains(word), "'{word}' missing from: {message}");
    }
    assert!(
        count.0 >= 1,
        "what was recorded before the blow-up was delivered"
    );
}
