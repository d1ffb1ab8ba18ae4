//! The keys of a non-isothermal run (docs/guide/scenario.md, "Non-isothermal runs"): the blank
//! out of the oven at `process.blank_temperature`, carried `process.transfer_time` seconds in
//! air, the tools at `tools.punch.temperature` etc., and the heat exchanges of `[thermal]`.
//! Values are given in the units of data sheets (W/(m²·K)) and kept in the program's.

use super::scenario::InterfaceLaw;
use super::scenario::Scenario;
use crate::contact::ply_contact::FilmFriction;
use crate::limits::{
    check_given, HEAT_TRANSFER, PRESSURE, PROCESS_TIME, TEMPERATURE, THERMAL_STEP,
};
use crate::material::MaterialCard;
use crate::solver::heat::{FrictionLaw, HeatModel, InterfaceFriction};
use crate::solver::{Model, SolverKind};
use crate::thermal::air::AirExchange;
use crate::thermal::blank::{heat_transfer, BlankHeat, HeatSettings, LayerKind, PlyHeat};
use crate::thermal::ThermalProperties;
use serde::Deserialize;
use std::path::Path;
use std::sync::Arc;

/// What a non-isothermal run adds to a scenario, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct HeatScenario {
    /// The blank out of the oven (°C).
    pub blank_temperature: f64,
    /// Seconds in air from the oven to the start of the stroke.
    pub transfer_time: f64,
    /// The tools' temperatures (°C): punch, die and, with a holder, the holder.
    pub punch: f64,
    pub die: f64,
    pub holder: Option<f64>,
    pub thermal: ThermalTable,
}

/// `[thermal]` as written: the exchanges of the blank with the room, the tools and between its
/// plies, and how finely the heat equation is resolved.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalTable {
    /// °C.
    #[serde(default = "default_room")]
    pub room_temperature: f64,
    /// Natural convection to still air, W/(m²·K).
    #[serde(default = "default_air_convection")]
    pub air_convection: f64,
    /// Between a ply and a tool, W/(m²·K): a number, or `[pressure MPa, h]` pairs at
    /// increasing pressures.
    #[serde(default = "default_contact_conductance")]
    pub contact_conductance: Conductance,
    /// Between two plies in contact, W/(m²·K).
    #[serde(default = "default_interply_conductance")]
    pub interply_conductance: f64,
    /// Cells through each layer of a ply.
    #[serde(default = "default_cells")]
    pub cells_per_layer: usize,
    /// Longest step of the heat equation (s of process time).
    #[serde(default = "default_time_step")]
    pub time_step: f64,
    /// Share of the friction work on the tools that heats the blank.
    #[serde(default = "default_friction_heat")]
    pub friction_heat_fraction: f64,
}

impl Default for ThermalTable {
    fn default() -> Self {
        Self {
            room_temperature: default_room(),
            air_convection: default_air_convection(),
            contact_conductance: default_contact_conductance(),
            interply_conductance: default_interply_conductance(),
            cells_per_layer: default_cells(),
            time_step: default_time_step(),
            friction_heat_fraction: default_friction_heat(),
        }
    }
}

/// A conductance: one number, or a table against the contact pressure.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Conductance {
    Constant(f64),
    Table(Vec<[f64; 2]>),
}

fn default_room() -> f64 {
    25.0
}

/// Natural convection from a horizontal plate in still air, 5-25 W/(m²·K); 10 is the usual
/// middle value (an ESTIMATE for a blank carried by a shuttle, which also moves the air).
fn default_air_convection() -> f64 {
    10.0
}

/// ESTIMATE of a molten prepreg on a polished steel tool: about 300 W/(m²·K) where it merely
/// touches, rising with the pressure that presses the melt into the tool's roughness, to about
/// 3000 W/(m²·K) at the 1-2 MPa of consolidation (the 300-3000 W/(m²·K) reported for
/// thermoplastic composites on steel tools).
fn default_contact_conductance() -> Conductance {
    Conductance::Table(vec![
        [0.0, 300.0],
        [0.1, 1000.0],
        [1.0, 2500.0],
        [2.0, 3000.0],
    ])
}

/// ESTIMATE: two molten plies in contact share a resin film, nearly a perfect contact; 3000
/// W/(m²·K) is the conductance of a 0.1 mm PPS film (0.3 W/(m·K) / 0.1 mm).
fn default_interply_conductance() -> f64 {
    3000.0
}

/// **(choice)** Three cells per layer, nine through an A:B:A ply: the skins' temperatures
/// within a few per cent of the converged ones on a tool (docs/model.md §9, "Resolution").
fn default_cells() -> usize {
    3
}

/// **(choice)** 10 ms: a ply on a tool changes its temperature by a few kelvin in that time.
fn default_time_step() -> f64 {
    0.01
}

/// **(choice)** Half the friction work heats the blank, half the tool: the usual split of
/// sliding contact between bodies of like effusivity.
fn default_friction_heat() -> f64 {
    0.5
}

impl ThermalTable {
    /// Each value in its range, the first outside named by its key.
    pub fn check(&self) -> Result<(), String> {
        check_given([
            (
                "thermal.room_temperature",
                Some(self.room_temperature),
                TEMPERATURE,
            ),
            (
                "thermal.air_convection",
                Some(self.air_convection),
                HEAT_TRANSFER,
            ),
            (
                "thermal.interply_conductance",
                Some(self.interply_conductance),
                HEAT_TRANSFER,
            ),
            ("thermal.time_step", Some(self.time_step), THERMAL_STEP),
            (
                "thermal.friction_heat_fraction",
                Some(self.friction_heat_fraction),
                crate::limits::FRACTION,
            ),
        ])?;
        if !(1..=20).contains(&self.cells_per_layer) {
            return Err(format!(
                "thermal.cells_per_layer = {} must be 1 to 20",
                self.cells_per_layer
            ));
        }
        self.conductance_table().map(|_| ())
    }

    /// `thermal.contact_conductance` as `(MPa, W/(m²·K))` pairs at increasing pressures.
    fn conductance_table(&self) -> Result<Vec<(f64, f64)>, String> {
        const KEY: &str = "thermal.contact_conductance";
        match &self.contact_conductance {
            Conductance::Constant(h) => {
                HEAT_TRANSFER.check(KEY, *h)?;
                Ok(vec![(0.0, *h)])
            }
            Conductance::Table(pairs) => {
                if pairs.is_empty() {
                    return Err(format!(
                        "{KEY} is a number, or [pressure MPa, W/(m²·K)] pairs: give one pair at \
                         least"
                    ));
                }
                for (i, [p, h]) in pairs.iter().enumerate() {
                    PRESSURE.check(&format!("{KEY} (pair {}, its pressure)", i + 1), *p)?;
                    HEAT_TRANSFER.check(&format!("{KEY} (pair {}, its conductance)", i + 1), *h)?;
                }
                if let Some(i) = pairs.windows(2).position(|w| w[1][0] <= w[0][0]) {
                    return Err(format!(
                        "{KEY}: the pressures must increase strictly (pair {} at {} MPa, pair {} \
                         at {} MPa)",
                        i + 1,
                        pairs[i][0],
                        i + 2,
                        pairs[i + 1][0]
                    ));
                }
                Ok(pairs.iter().map(|&[p, h]| (p, h)).collect())
            }
        }
    }

    /// The settings of the heat equation in the program's units; `emissivity` is each ply's
    /// own (its card's), set per face when the field is advanced.
    pub fn settings(&self) -> Result<HeatSettings, String> {
        let table = self.conductance_table()?;
        Ok(HeatSettings {
            cells_per_layer: self.cells_per_layer,
            time_step: self.time_step,
            air: AirExchange {
                convection: heat_transfer(self.air_convection),
                emissivity: 0.0,
                room_temperature: self.room_temperature,
            },
            contact_conductance: table
                .into_iter()
                .map(|(p, h)| (p, heat_transfer(h)))
                .collect(),
            interply_conductance: heat_transfer(self.interply_conductance),
            friction_heat_fraction: self.friction_heat_fraction,
        })
    }
}

/// The tools' `temperature` keys as written (`tools.punch.temperature` etc.).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ToolTemperatures {
    pub punch: Option<f64>,
    pub die: Option<f64>,
    pub holder: Option<f64>,
}

/// The heat keys of a scenario, checked: `None` for an isothermal run (no
/// `process.blank_temperature`), where every other heat key is refused.
pub fn heat_scenario(
    blank_temperature: Option<f64>,
    transfer_time: Option<f64>,
    tools: ToolTemperatures,
    thermal: Option<ThermalTable>,
    has_holder: bool,
) -> Result<Option<HeatScenario>, String> {
    let Some(blank_temperature) = blank_temperature else {
        let stray = [
            ("process.transfer_time", transfer_time.is_some()),
            ("tools.punch.temperature", tools.punch.is_some()),
            ("tools.die.temperature", tools.die.is_some()),
            ("tools.holder.temperature", tools.holder.is_some()),
            ("[thermal]", thermal.is_some()),
        ];
        if let Some((key, _)) = stray.iter().find(|(_, given)| *given) {
            return Err(format!(
                "{key} belongs to a non-isothermal run: give process.blank_temperature (the \
                 blank out of the oven, °C) instead of process.temperature, or leave {key} out"
            ));
        }
        return Ok(None);
    };
    let transfer_time = transfer_time.unwrap_or(0.0);
    check_given([
        (
            "process.blank_temperature",
            Some(blank_temperature),
            TEMPERATURE,
        ),
        ("process.transfer_time", Some(transfer_time), PROCESS_TIME),
        ("tools.punch.temperature", tools.punch, TEMPERATURE),
        ("tools.die.temperature", tools.die, TEMPERATURE),
        ("tools.holder.temperature", tools.holder, TEMPERATURE),
    ])?;
    let need = |key: &str, t: Option<f64>| {
        t.ok_or_else(|| {
            format!(
                "{key} is needed in a non-isothermal run (process.blank_temperature is given): \
                 the tool's temperature, °C (or tools.temperature for every tool)"
            )
        })
    };
    let thermal = thermal.unwrap_or_default();
    thermal.check()?;
    Ok(Some(HeatScenario {
        blank_temperature,
        transfer_time,
        punch: need("tools.punch.temperature", tools.punch)?,
        die: need("tools.die.temperature", tools.die)?,
        holder: match has_holder {
            true => Some(need("tools.holder.temperature", tools.holder)?),
            false => tools.holder,
        },
        thermal,
    }))
}

/// The heat problem of `model`, the blank of `s` on the plies' `cards` (one per ply, in the
/// model's order), its tools in the order punch, die, holder: every card must have a
/// `[thermal]` section and every table must hold from the coldest tool to the blank out of the
/// oven, or the run is refused before it starts, naming the key.
pub fn heat_model(
    s: &Scenario,
    heat: &HeatScenario,
    cards: &[(&MaterialCard, &Path)],
    model: &Model,
) -> Result<HeatModel, String> {
    let mut tools = vec![("tools.punch.temperature", heat.punch)];
    tools.push(("tools.die.temperature", heat.die));
    if model.tools.len() > 2 {
        let holder = heat.holder.ok_or("tools.holder.temperature is needed")?;
        tools.push(("tools.holder.temperature", holder));
    }
    if let Some(layup) = &s.blank.layup {
        // a face of the stack can cool to the coldest tool: the film's tables must hold there
        for law in &layup.laws {
            for &(key, t) in &tools {
                law.at(t).map_err(|e| format!("{key} = {t} °C: {e}"))?;
            }
        }
    }
    let mut plies = Vec::with_capacity(model.plies.len());
    for (ply, &(card, path)) in model.plies.iter().zip(cards) {
        let refuse = |e: String| format!("{e} (card {})", path.display());
        let Some(properties) = &card.thermal else {
            return Err(refuse(
                "the card has no [thermal] section, which a non-isothermal run \
                 (process.blank_temperature) needs: the ply's specific heat and conductivities"
                    .into(),
            ));
        };
        check_card_temperatures(card, properties, heat, &tools).map_err(refuse)?;
        let layers = ply
            .laminate
            .layers()
            .iter()
            .map(|l| match l.law.name() {
                "fabric" => (LayerKind::Fabric, l.thickness),
                _ => (LayerKind::Matrix, l.thickness),
            })
            .collect();
        plies.push(PlyHeat {
            properties: properties.clone(),
            density: card.density,
            layers,
        });
    }
    let elements = model.elements.iter().map(|e| e.nodes().to_vec()).collect();
    let element_ply = (0..model.elements.len())
        .map(|k| model.ply_index(k))
        .collect();
    let blank = BlankHeat::new(
        plies,
        elements,
        element_ply,
        &model.mesh.nodes,
        tools.iter().map(|&(_, t)| t).collect(),
        heat.thermal.settings()?,
    )?;
    Ok(HeatModel {
        blank,
        blank_temperature: heat.blank_temperature,
        transfer_time: heat.transfer_time,
        time_scaling: match s.process.solver {
            SolverKind::Explicit => s.process.time_scaling,
            SolverKind::Implicit => 1.0,
        },
        bending: cards.iter().map(|(c, _)| c.bending.clone()).collect(),
        card_ranges: cards.iter().map(|(c, _)| c.temperature_range()).collect(),
        interface_friction: interface_friction(s),
    })
}

/// Each interface's law of a layup, at the physical speeds scaled as the model's interfaces are
/// (`layup::layup_model`); none for one ply.
fn interface_friction(s: &Scenario) -> Vec<InterfaceFriction> {
    let Some(layup) = &s.blank.layup else {
        return Vec::new();
    };
    layup
        .laws
        .iter()
        .map(|law| {
            Arc::new(ScaledLaw {
                law: law.clone(),
                time_scaling: s.process.time_scaling,
            }) as InterfaceFriction
        })
        .collect()
}

/// An interface's law at the physical speeds, its film scaled for a run `time_scaling` times
/// faster (docs/model.md §6).
#[derive(Debug)]
struct ScaledLaw {
    law: InterfaceLaw,
    time_scaling: f64,
}

impl FrictionLaw for ScaledLaw {
    fn at(&self, temperature: f64) -> Result<FilmFriction, String> {
        self.law
            .at(temperature)
            .map(|f| f.time_scaled(self.time_scaling))
    }
}

/// The card's tables hold at the blank out of the oven and at every tool's temperature (the
/// coldest a face can get on a tool): its mechanical tables, its specific heat and, where it
/// crystallises, its rate table.
fn check_card_temperatures(
    card: &MaterialCard,
    properties: &ThermalProperties,
    heat: &HeatScenario,
    tools: &[(&str, f64)],
) -> Result<(), String> {
    let given = std::iter::once(("process.blank_temperature", heat.blank_temperature))
        .chain(tools.iter().copied());
    for (key, t) in given {
        card.check_temperature(key, t)?;
        properties
            .specific_heat
            .at(t)
            .map_err(|e| format!("{key}: {e}"))?;
        if let Some(c) = &properties.crystallisation {
            c.kinetics
                .rate(t)
                .map_err(|e| format!("{key} = {t} °C: {e}"))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tools() -> ToolTemperatures {
        ToolTemperatures {
            punch: Some(170.0),
            die: Some(170.0),
            holder: Some(170.0),
        }
    }

    /// A tool's temperature without a blank temperature is refused, naming both keys.
    #[test]
    fn heat_keys_need_a_blank_temperature() {
        let e = heat_scenario(None, None, tools(), None, true).unwrap_err();
        assert!(
            e.contains("tools.punch.temperature") && e.contains("process.blank_temperature"),
            "{e}"
        );
    }

    /// A missing tool temperature is named.
    #[test]
    fn every_tool_needs_a_temperature() {
        let mut t = tools();
        t.die = None;
        let e = heat_scenario(Some(320.0), Some(5.0), t, None, true).unwrap_err();
        assert!(e.contains("tools.die.temperature is needed"), "{e}");
    }

    /// A negative conductance and pressures out of order are refused by key.
    #[test]
    fn bad_conductances_are_named() {
        let mut thermal = ThermalTable {
            interply_conductance: -1.0,
            ..ThermalTable::default()
        };
        let e = heat_scenario(Some(320.0), None, tools(), Some(thermal.clone()), true).unwrap_err();
        assert!(e.contains("thermal.interply_conductance"), "{e}");
        thermal.interply_conductance = 1000.0;
        thermal.contact_conductance = Conductance::Table(vec![[1.0, 500.0], [0.5, 900.0]]);
        let e = heat_scenario(Some(320.0), None, tools(), Some(thermal), true).unwrap_err();
        assert!(
            e.contains("thermal.contact_conductance") && e.contains("increase"),
            "{e}"
        );
    }

    /// The conductance table is interpolated in pressure and held beyond its ends, in the
    /// program's units (1000 W/(m²·K) = 1 N/(mm·s·K)).
    #[test]
    fn contact_conductance_follows_the_pressure() {
        let thermal = ThermalTable {
            contact_conductance: Conductance::Table(vec![[0.0, 1000.0], [1.0, 3000.0]]),
            ..ThermalTable::default()
        };
        let s = thermal.settings().unwrap();
        assert!((s.contact_conductance_at(0.5) - 2.0).abs() < 1e-12);
        assert!((s.contact_conductance_at(5.0) - 3.0).abs() < 1e-12);
        assert!((s.contact_conductance_at(0.0) - 1.0).abs() < 1e-12);
    }
}
