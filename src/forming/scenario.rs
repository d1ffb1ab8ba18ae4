//! The scenario file of a forming run: blank, tools, process and outputs, read from TOML and
//! checked. Unknown keys and inconsistent values are errors that name the key; any scalar can
//! be overridden from the command line (`--set process.temperature=310`).

use super::heat::{heat_scenario, HeatScenario, ThermalTable, ToolTemperatures};
use super::motion::{MotionTable, Stage};
use super::supports::{GripperTable, SpringTable, SupportScenario};
use crate::contact::ply_contact::FilmFriction;
use crate::io::{from_toml_text, from_toml_value};
use crate::limits::{
    check_given, shown, shown_apart, Range, ANGLE, FILM_CONSISTENCY, FILM_CUTOFF_RATE, FILM_INDEX,
    FILM_THICKNESS, FILM_TRANSITION_STRESS, FILM_VISCOSITY, FILM_YIELD, FORCE, FRAMES, FRICTION,
    GAP, HISTORY_POINTS, LENGTH, SHEAR_ANGLE, SPEED, TEMPERATURE, TIME_SCALING, TIME_STEP,
};
use crate::material::TemperatureTable;
use crate::mesh::DiagonalPattern;
use crate::solver::SolverKind;
use nalgebra::Vector3;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A scenario read and checked; paths resolved against the scenario's folder.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    pub origin: String,
    pub blank: Blank,
    pub boundary: Vec<Boundary>,
    pub tools: ToolSet,
    pub process: Process,
    pub output: Output,
    /// The blank's temperature field of a non-isothermal run; `None`: isothermal at
    /// `process.temperature`.
    pub heat: Option<HeatScenario>,
    /// Each tool's own `motion` table (punch, die, holder), where given.
    pub motions: [Option<MotionTable>; 3],
    /// Springs, grippers and gravity.
    pub supports: SupportScenario,
    /// Tools besides the punch, die and holder, their files resolved.
    pub extra_tools: Vec<ExtraTool>,
}

/// The blank: one ply of one material card, or a layup of plies, either a rectangle meshed
/// here or a mesh file (every ply of a layup has the blank's outline).
#[derive(Clone, Debug, PartialEq)]
pub struct Blank {
    /// Material card (TOML), relative to the scenario file: the blank's, or the default of the
    /// plies of a layup.
    pub card: PathBuf,
    pub shape: BlankShape,
    /// Warp angle (degrees): the reference direction turned by it about z.
    pub ply_angle: f64,
    /// Reference direction of the warp (global, unit), projected onto each element
    /// (`mesh::orientation`); a mesh file's own orientations take precedence.
    pub reference_direction: Vector3<f64>,
    /// The plies of a layup (`blank.ply_angles` or `[[blank.plies]]`), from the punch's side;
    /// `None` for the blank of one ply.
    pub layup: Option<Layup>,
}

/// The plies of a layup and the friction between them.
#[derive(Clone, Debug, PartialEq)]
pub struct Layup {
    pub plies: Vec<PlySpec>,
    /// The friction between each two neighbouring plies, from the punch's side (one fewer than
    /// the plies): `blank.interply`'s, or a `[[blank.interfaces]]` table's where one names the
    /// pair; at `process.temperature` and the physical speeds (the solver's time scaling is
    /// applied when the model is built).
    pub interfaces: Vec<FilmFriction>,
    /// The law of each interface as written, which a non-isothermal run evaluates at the
    /// interface's temperature as the run goes.
    pub laws: Vec<InterfaceLaw>,
    /// Whether the plies came as `blank.ply_angles` (the keys named in messages).
    pub from_angles: bool,
}

/// One ply of a layup.
#[derive(Clone, Debug, PartialEq)]
pub struct PlySpec {
    pub name: String,
    /// Its card, resolved against the scenario's folder (the blank's by default).
    pub card: PathBuf,
    /// Its warp angle (degrees) from the blank's reference direction.
    pub angle: f64,
    /// Its own outline (a rectangle of the blank's element size and pattern, or a mesh file);
    /// `None`: the blank's.
    pub shape: Option<BlankShape>,
}

/// `[[blank.plies]]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlyTable {
    angle: f64,
    card: Option<PathBuf>,
    name: Option<String>,
    width: Option<f64>,
    length: Option<f64>,
    mesh: Option<PathBuf>,
    element_set: Option<String>,
}

impl PlyTable {
    /// The ply's own outline, if it has one (`key` its table's, `blank` the blank's shape),
    /// paths resolved against `folder`.
    fn shape(
        &self,
        key: &str,
        blank: &BlankShape,
        folder: &Path,
    ) -> Result<Option<BlankShape>, String> {
        match (&self.mesh, self.width, self.length) {
            (Some(mesh), None, None) => Ok(Some(BlankShape::File {
                mesh: folder.join(mesh),
                element_set: self.element_set.clone(),
            })),
            (Some(_), _, _) => Err(format!(
                "{key}.mesh gives the ply's outline, and so do its width and length: keep one"
            )),
            (None, ..) if self.element_set.is_some() => Err(format!(
                "{key}.element_set names a set of {key}.mesh, which is not given"
            )),
            (None, None, None) => Ok(None),
            (None, Some(width), Some(length)) => match blank {
                BlankShape::Rectangle {
                    element_size,
                    pattern,
                    ..
                } => Ok(Some(BlankShape::Rectangle {
                    width,
                    length,
                    element_size: *element_size,
                    pattern: *pattern,
                })),
                BlankShape::File { .. } => Err(format!(
                    "{key}.width: a ply's own rectangle is meshed at blank.element_size, and the \
                     blank is read from blank.mesh: give the ply a mesh file ({key}.mesh) instead"
                )),
            },
            (None, ..) => Err(format!(
                "{key}.width and length go together: the ply's own rectangle, centred on the \
                 punch's axis"
            )),
        }
    }
}

/// The friction law of one interface as written (`blank.interply` or a `[[blank.interfaces]]`
/// table), at any temperature: its values at the physical speeds, checked as the scenario's.
#[derive(Clone, Debug, PartialEq)]
pub struct InterfaceLaw {
    key: String,
    table: InterplyTable,
}

impl InterfaceLaw {
    /// The friction at `temperature` (°C); outside a table an error naming the key.
    pub fn at(&self, temperature: f64) -> Result<FilmFriction, String> {
        self.table.friction(&self.key, temperature)
    }
}

/// `[blank.interply]` or a `[[blank.interfaces]]` table as written: Eqs. (F1)–(F3) of
/// docs/model.md. `friction`,
/// `film_viscosity`, `film_consistency` and `yield_stress` are numbers or tables of
/// `[temperature °C, value]` pairs ([`ByTemperature`]), taken at `process.temperature`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct InterplyTable {
    /// `[[blank.interfaces]]` only: the two neighbouring plies the table is between.
    between: Option<[PlyRef; 2]>,
    friction: ByTemperature,
    /// `"newtonian"` (the default), `"power-law"` or `"cross"`.
    film_law: Option<FilmLaw>,
    /// The film's viscosity (Pa·s; Cross: at a vanishing rate) and thickness (mm).
    film_viscosity: Option<ByTemperature>,
    film_thickness: Option<f64>,
    /// Power law: `K` (Pa·s^n) and the cut-off rate (1/s, default [`DEFAULT_CUTOFF_RATE`]).
    film_consistency: Option<ByTemperature>,
    film_cutoff_rate: Option<f64>,
    /// Power law and Cross: `n`.
    film_index: Option<f64>,
    /// Cross: `tau_star` (MPa).
    film_transition_stress: Option<f64>,
    /// The film's yield stress (MPa).
    yield_stress: Option<ByTemperature>,
}

/// A ply named in `[[blank.interfaces]]`: its place from the punch's side (from 1) or its name.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
enum PlyRef {
    Place(i64),
    Name(String),
}

impl PlyRef {
    /// The index of the ply among `plies`, or why there is none.
    fn index(&self, plies: &[PlySpec]) -> Result<usize, String> {
        match self {
            Self::Place(k) if *k >= 1 && (*k as usize) <= plies.len() => Ok(*k as usize - 1),
            Self::Place(k) => Err(format!(
                "names ply {k}; the layup has plies 1 to {}",
                plies.len()
            )),
            Self::Name(name) => plies.iter().position(|p| &p.name == name).ok_or_else(|| {
                let names: Vec<String> = plies.iter().map(|p| format!("\"{}\"", p.name)).collect();
                format!(
                    "names no ply of the layup: \"{name}\" is not one of {}",
                    names.join(", ")
                )
            }),
        }
    }
}

/// How the film's viscosity depends on its shear rate (docs/model.md Eqs. (F1)–(F3)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(rename_all = "kebab-case")]
enum FilmLaw {
    #[default]
    Newtonian,
    PowerLaw,
    Cross,
}

impl FilmLaw {
    fn name(self) -> &'static str {
        match self {
            Self::Newtonian => "newtonian",
            Self::PowerLaw => "power-law",
            Self::Cross => "cross",
        }
    }

    /// The film keys the law needs, and those it may take besides.
    fn keys(self) -> (&'static [&'static str], &'static [&'static str]) {
        match self {
            Self::Newtonian => (&[], &["film_viscosity", "film_thickness"]),
            Self::PowerLaw => (
                &["film_consistency", "film_index", "film_thickness"],
                &["film_cutoff_rate"],
            ),
            Self::Cross => (
                &[
                    "film_viscosity",
                    "film_index",
                    "film_transition_stress",
                    "film_thickness",
                ],
                &[],
            ),
        }
    }
}

/// The cut-off rate of a power-law film where none is given (1/s): the film is Newtonian below
/// it, at `K` (docs/model.md Eq. (F2)).
pub const DEFAULT_CUTOFF_RATE: f64 = 1.0;

/// A value of `[blank.interply]`: a number, or `[temperature °C, value]` pairs at increasing
/// temperatures, interpolated linearly at the run's temperature (as a card's tables are,
/// docs/model.md §2) and never extrapolated.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(
    untagged,
    expecting = "a number, or a list of [temperature °C, value] pairs at increasing \
                 temperatures, such as [[280.0, 0.3], [320.0, 0.2]]"
)]
enum ByTemperature {
    Number(f64),
    Table(Vec<[f64; 2]>),
}

impl ByTemperature {
    /// The value of `key` at `temperature` (°C), every value given within `range`.
    fn at(&self, key: &str, range: Range, temperature: f64) -> Result<f64, String> {
        let pairs = match self {
            Self::Number(value) => {
                range.check(key, *value)?;
                return Ok(*value);
            }
            Self::Table(pairs) => pairs,
        };
        for (i, &[t, value]) in pairs.iter().enumerate() {
            TEMPERATURE.check(&format!("{key} (pair {}, its temperature)", i + 1), t)?;
            range.check(
                &format!("{key} (pair {}, at {} °C)", i + 1, shown(t)),
                value,
            )?;
        }
        let (temperatures, values) = pairs.iter().map(|&[t, v]| (t, v)).unzip();
        let table = TemperatureTable::new(key, temperatures, values)?;
        table.at(temperature).map_err(|_| {
            let (low, high) = table.range();
            format!(
                "{key} is given from {} to {} °C, and process.temperature = {} °C lies \
                 outside: extend the table (it is never extrapolated) or form within it",
                shown(low),
                shown(high),
                shown_apart(temperature, if temperature < low { low } else { high })
            )
        })
    }
}

impl InterplyTable {
    /// The friction at `temperature` (°C), every value within its range, the film's keys
    /// those of its law.
    fn friction(&self, table: &str, temperature: f64) -> Result<FilmFriction, String> {
        let key = |name: &str| format!("{table}.{name}");
        let mu = self.friction.at(&key("friction"), FRICTION, temperature)?;
        let shear_cap = match &self.yield_stress {
            Some(cap) => cap.at(&key("yield_stress"), FILM_YIELD, temperature)?,
            None => f64::INFINITY,
        };
        let law = self.film_law.unwrap_or_default();
        self.check_film_keys(table, law)?;
        // Pa·s (and Pa·s^n) to the MPa·s of the model's units
        const PA: f64 = 1e-6;
        // check_film_keys has asked a shear-thinning film for its thickness
        let Some(h) = self.film_thickness else {
            return Ok(FilmFriction::newtonian(mu, 0.0, shear_cap));
        };
        FILM_THICKNESS.check(&key("film_thickness"), h)?;
        Ok(match law {
            FilmLaw::Newtonian => {
                let eta = self.viscosity(table, temperature)?;
                FilmFriction::newtonian(mu, PA * eta / h, shear_cap)
            }
            FilmLaw::PowerLaw => {
                let consistency = match &self.film_consistency {
                    Some(k) => k.at(&key("film_consistency"), FILM_CONSISTENCY, temperature)?,
                    None => f64::NAN,
                };
                let cutoff = self.film_cutoff_rate.unwrap_or(DEFAULT_CUTOFF_RATE);
                FILM_CUTOFF_RATE.check(&key("film_cutoff_rate"), cutoff)?;
                let law = (PA * consistency, self.index(table)?, cutoff);
                FilmFriction::power_law(mu, law, h, shear_cap)
            }
            FilmLaw::Cross => {
                let eta0 = self.viscosity(table, temperature)?;
                let tau_star = self.film_transition_stress.unwrap_or(f64::NAN);
                FILM_TRANSITION_STRESS.check(&key("film_transition_stress"), tau_star)?;
                FilmFriction::cross(mu, (PA * eta0, self.index(table)?, tau_star), h, shear_cap)
            }
        })
    }

    /// `film_index`, `n`.
    fn index(&self, table: &str) -> Result<f64, String> {
        let n = self.film_index.unwrap_or(f64::NAN);
        FILM_INDEX.check(&format!("{table}.film_index"), n)?;
        Ok(n)
    }

    /// `film_viscosity` at `temperature` (Pa·s).
    fn viscosity(&self, table: &str, temperature: f64) -> Result<f64, String> {
        let eta = self.film_viscosity.as_ref().ok_or("no film_viscosity")?;
        eta.at(
            &format!("{table}.film_viscosity"),
            FILM_VISCOSITY,
            temperature,
        )
    }

    /// The film keys given are those of `law`: all it needs (for a Newtonian film, both of its
    /// keys or neither), none of another law's.
    fn check_film_keys(&self, table: &str, law: FilmLaw) -> Result<(), String> {
        let given = [
            ("film_viscosity", self.film_viscosity.is_some()),
            ("film_thickness", self.film_thickness.is_some()),
            ("film_consistency", self.film_consistency.is_some()),
            ("film_cutoff_rate", self.film_cutoff_rate.is_some()),
            ("film_index", self.film_index.is_some()),
            (
                "film_transition_stress",
                self.film_transition_stress.is_some(),
            ),
        ];
        let (needed, optional) = law.keys();
        let law_named = match self.film_law {
            Some(law) => format!("film_law = \"{}\"", law.name()),
            None => "a Newtonian film (no film_law)".into(),
        };
        for (name, _) in given.iter().filter(|(_, g)| *g) {
            if !needed.contains(name) && !optional.contains(name) {
                return Err(format!(
                    "{table}.{name} is not a key of {law_named}: {} (docs/forming.md, \
                     \"Layups\")",
                    owner_of(name)
                ));
            }
        }
        if law == FilmLaw::Newtonian {
            if self.film_viscosity.is_some() != self.film_thickness.is_some() {
                return Err(format!(
                    "{table}.film_viscosity and film_thickness go together: give both, or \
                     neither for Coulomb friction alone"
                ));
            }
            return Ok(());
        }
        match needed
            .iter()
            .find(|n| !given.iter().any(|(g, set)| g == *n && *set))
        {
            Some(name) => Err(format!(
                "{table}.{name} is needed by {law_named} (docs/forming.md, \"Layups\")"
            )),
            None => Ok(()),
        }
    }
}

/// Which `film_law` a film key belongs to, said when it is given to another.
fn owner_of(key: &str) -> &'static str {
    match key {
        "film_consistency" | "film_cutoff_rate" => {
            "it belongs to film_law = \"power-law\" (a Newtonian or Cross film takes \
             film_viscosity)"
        }
        "film_transition_stress" => "it belongs to film_law = \"cross\"",
        "film_index" => "it belongs to film_law = \"power-law\" or \"cross\"",
        _ => "a power-law film takes film_consistency (K, Pa·s^n) instead",
    }
}

/// Where the blank's mesh comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum BlankShape {
    /// Size along x and y (mm), centred on the punch axis; target element size (mm); cells cut
    /// by `pattern` (4-node quadrilaterals by default: no preferred fold line, see
    /// docs/model.md §4).
    Rectangle {
        width: f64,
        length: f64,
        element_size: f64,
        pattern: DiagonalPattern,
    },
    /// A Gmsh `.msh` or Abaqus `.inp` file (relative to the scenario), in mm, its mid-plane as
    /// at the start of the stroke; only the elements of `element_set` when one is named.
    File {
        mesh: PathBuf,
        element_set: Option<String>,
    },
}

/// The `[blank]` table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BlankTable {
    card: PathBuf,
    width: Option<f64>,
    length: Option<f64>,
    element_size: Option<f64>,
    pattern: Option<DiagonalPattern>,
    mesh: Option<PathBuf>,
    element_set: Option<String>,
    ply_angle: Option<f64>,
    reference_direction: Option<[f64; 3]>,
    ply_angles: Option<Vec<f64>>,
    plies: Option<Vec<PlyTable>>,
    interply: Option<InterplyTable>,
    interfaces: Option<Vec<InterplyTable>>,
}

impl BlankTable {
    /// The blank, paths resolved against `folder`: a rectangle or a file, never both; a
    /// layup's friction taken at the run's `temperature` (°C).
    fn resolve(self, folder: &Path, temperature: f64) -> Result<Blank, String> {
        let card = folder.join(&self.card);
        let shape = match &self.mesh {
            Some(mesh) => {
                let rectangle_keys = [
                    ("width", self.width.is_some()),
                    ("length", self.length.is_some()),
                    ("element_size", self.element_size.is_some()),
                    ("pattern", self.pattern.is_some()),
                ];
                if let Some((key, _)) = rectangle_keys.iter().find(|(_, given)| *given) {
                    return Err(format!(
                        "blank.{key} is for the built-in rectangle; a blank read from blank.mesh \
                         takes its size from the file: remove one of them"
                    ));
                }
                BlankShape::File {
                    mesh: folder.join(mesh),
                    element_set: self.element_set.clone(),
                }
            }
            None => {
                if self.element_set.is_some() {
                    return Err(
                        "blank.element_set names a set of blank.mesh, which is not given".into(),
                    );
                }
                let need = |key: &str, v: Option<f64>| {
                    v.ok_or_else(|| {
                        format!(
                            "blank.{key} is needed (or blank.mesh = \"file.msh\" or \
                             \"file.inp\" for a meshed blank)"
                        )
                    })
                };
                BlankShape::Rectangle {
                    width: need("width", self.width)?,
                    length: need("length", self.length)?,
                    element_size: need("element_size", self.element_size)?,
                    pattern: self.pattern.unwrap_or(DiagonalPattern::Quad),
                }
            }
        };
        let layup = self.layup((&card, &shape), folder, temperature)?;
        Ok(Blank {
            card,
            shape,
            ply_angle: self.ply_angle.unwrap_or(0.0),
            reference_direction: unit_direction(self.reference_direction)?,
            layup,
        })
    }

    /// The layup of `blank.ply_angles` or `[[blank.plies]]` (never both), with
    /// `blank.interply` at `temperature` (°C); `None` for one ply.
    fn layup(
        &self,
        (card, shape): (&Path, &BlankShape),
        folder: &Path,
        temperature: f64,
    ) -> Result<Option<Layup>, String> {
        let plies: Vec<PlySpec> = match (&self.ply_angles, &self.plies) {
            (Some(_), Some(_)) => {
                return Err(
                    "blank.ply_angles and [[blank.plies]] both give the layup: keep one \
                     (ply_angles for one card and a list of angles, [[blank.plies]] for a card \
                     or a name per ply)"
                        .into(),
                )
            }
            (None, None) => {
                let given = [
                    ("blank.interply", self.interply.is_some()),
                    ("[[blank.interfaces]]", self.interfaces.is_some()),
                ];
                if let Some((key, _)) = given.iter().find(|(_, g)| *g) {
                    return Err(format!(
                        "{key} is the friction between plies, and the blank has one ply: give \
                         blank.ply_angles or [[blank.plies]], or remove it"
                    ));
                }
                return Ok(None);
            }
            (Some(angles), None) => angles
                .iter()
                .enumerate()
                .map(|(i, &angle)| PlySpec {
                    name: format!("ply {}", i + 1),
                    card: card.to_path_buf(),
                    angle,
                    shape: None,
                })
                .collect(),
            (None, Some(tables)) => tables
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    Ok(PlySpec {
                        name: t.name.clone().unwrap_or_else(|| format!("ply {}", i + 1)),
                        card: t
                            .card
                            .as_ref()
                            .map_or(card.to_path_buf(), |c| folder.join(c)),
                        angle: t.angle,
                        shape: t.shape(&format!("blank.plies[{}]", i + 1), shape, folder)?,
                    })
                })
                .collect::<Result<_, String>>()?,
        };
        let key = if self.ply_angles.is_some() {
            "blank.ply_angles"
        } else {
            "blank.plies"
        };
        if plies.len() < 2 {
            return Err(format!(
                "{key} gives {} plies: a layup has two or more (a blank of one ply takes \
                 blank.ply_angle)",
                plies.len()
            ));
        }
        if self.ply_angle.is_some() {
            return Err(format!(
                "blank.ply_angle is the angle of a blank of one ply; {key} gives each ply's: \
                 remove blank.ply_angle"
            ));
        }
        for (i, a) in plies.iter().enumerate() {
            if plies[..i].iter().any(|b| b.name == a.name) {
                return Err(format!("blank.plies: two plies are named \"{}\"", a.name));
            }
        }
        // a table is read at the run's temperature: that must be a temperature first
        TEMPERATURE.check("process.temperature", temperature)?;
        let (interfaces, laws) = self.interfaces(&plies, temperature)?;
        Ok(Some(Layup {
            plies,
            interfaces,
            laws,
            from_angles: self.ply_angles.is_some(),
        }))
    }

    /// The friction between each two neighbouring `plies` at `temperature` (°C), and each
    /// pair's law: `[[blank.interfaces]]`'s where a table names the pair, `blank.interply`'s
    /// elsewhere.
    fn interfaces(
        &self,
        plies: &[PlySpec],
        temperature: f64,
    ) -> Result<(Vec<FilmFriction>, Vec<InterfaceLaw>), String> {
        let mut own: Vec<Option<(FilmFriction, InterfaceLaw)>> = vec![None; plies.len() - 1];
        for (i, table) in self.interfaces.iter().flatten().enumerate() {
            let key = format!("blank.interfaces[{}]", i + 1);
            let lower = table.neighbours(&key, plies)?;
            if own[lower].is_some() {
                return Err(format!(
                    "{key}.between: plies {} and {} have a table before it: give each pair one",
                    lower + 1,
                    lower + 2
                ));
            }
            let friction = table.friction(&key, temperature)?;
            own[lower] = Some((
                friction,
                InterfaceLaw {
                    key,
                    table: table.clone(),
                },
            ));
        }
        if let Some(table) = &self.interply {
            if table.between.is_some() {
                return Err(
                    "blank.interply.between is not a key: blank.interply is the \
                            friction between every two plies that no [[blank.interfaces]] \
                            table names"
                        .into(),
                );
            }
        }
        let default = match &self.interply {
            Some(table) => Some((
                table.friction("blank.interply", temperature)?,
                InterfaceLaw {
                    key: "blank.interply".into(),
                    table: table.clone(),
                },
            )),
            None => None,
        };
        own.into_iter()
            .map(|f| {
                f.or_else(|| default.clone()).ok_or_else(|| {
                    "a layup needs blank.interply.friction, the Coulomb friction between its \
                     plies (docs/model.md, \"Friction through the molten film\"), unless a \
                     [[blank.interfaces]] table gives every pair's"
                        .to_string()
                })
            })
            .collect::<Result<Vec<_>, _>>()
            .map(|pairs| pairs.into_iter().unzip())
    }
}

impl InterplyTable {
    /// The index of the lower of the two neighbouring plies `between` names, in
    /// `[[blank.interfaces]]` table `key`.
    fn neighbours(&self, key: &str, plies: &[PlySpec]) -> Result<usize, String> {
        let Some([a, b]) = &self.between else {
            return Err(format!(
                "{key}.between is needed: the two neighbouring plies the table is between, by \
                 place from the punch's side (between = [1, 2]) or by name"
            ));
        };
        let [a, b] = [a, b].map(|p| p.index(plies).map_err(|e| format!("{key}.between {e}")));
        let (a, b) = (a?, b?);
        if a.abs_diff(b) != 1 {
            return Err(format!(
                "{key}.between gives plies {} and {}: an interface is between two neighbouring \
                 plies (places one apart)",
                a + 1,
                b + 1
            ));
        }
        Ok(a.min(b))
    }
}

/// `blank.reference_direction` (default x) as a unit vector. Only its direction counts, but a
/// vector whose length overflows (`[1e300, 1e300, 0]`) or underflows (`[1e-200, 0, 0]`) has
/// none that can be computed: refused, as is the zero vector.
fn unit_direction(given: Option<[f64; 3]>) -> Result<Vector3<f64>, String> {
    let direction = Vector3::from(given.unwrap_or([1.0, 0.0, 0.0]));
    let unit = direction / direction.norm();
    if unit.iter().all(|c| c.is_finite()) && (unit.norm() - 1.0).abs() < 1e-9 {
        return Ok(unit);
    }
    let components: Vec<String> = direction.iter().map(|&c| shown(c)).collect();
    Err(format!(
        "blank.reference_direction = [{}] has no direction that can be computed (its length \
         is zero, not a number, or beyond what a number holds): give a non-zero vector of \
         ordinary size, such as [1, 0, 0]",
        components.join(", ")
    ))
}

/// A node or element set of the blank's mesh held along some axes (a symmetry plane, a
/// clamp): the `[[boundary]]` tables.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Boundary {
    /// A node set of the mesh (the built-in rectangle has bottom, top, left, right, all) ...
    pub node_set: Option<String>,
    /// ... or an element set, whose nodes are held.
    pub element_set: Option<String>,
    /// Axes held: any of "x", "y", "z".
    pub held: Vec<String>,
}

/// Whether a boundary names a node or an element set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetKind {
    Node,
    Element,
}

impl Boundary {
    /// The held axes as a mask (x, y, z), checked.
    pub fn mask(&self) -> Result<[bool; 3], String> {
        let mut mask = [false; 3];
        for axis in &self.held {
            let k = match axis.as_str() {
                "x" => 0,
                "y" => 1,
                "z" => 2,
                other => {
                    return Err(format!(
                        "boundary.held: \"{other}\" is not an axis; use \"x\", \"y\" or \"z\""
                    ))
                }
            };
            mask[k] = true;
        }
        if mask == [false; 3] {
            return Err("boundary.held is empty: name the axes held (\"x\", \"y\", \"z\")".into());
        }
        Ok(mask)
    }

    /// The set's name and kind: exactly one of the two is given.
    pub fn set(&self) -> Result<(&str, SetKind), String> {
        match (&self.node_set, &self.element_set) {
            (Some(n), None) => Ok((n, SetKind::Node)),
            (None, Some(e)) => Ok((e, SetKind::Element)),
            _ => Err("each [[boundary]] names one node_set or one element_set".into()),
        }
    }
}

/// The tools: the built-in set ([`Tools`]) or surfaces read from files ([`ToolFiles`]).
#[derive(Clone, Debug, PartialEq)]
pub enum ToolSet {
    BuiltIn(Tools),
    Files(ToolFiles),
}

/// The built-in tool set: a hemispherical (or double-dome) punch, a die with a round (or
/// stadium-shaped) opening and a flat blank holder around it (`contact::tools`).
#[derive(Clone, Debug, PartialEq)]
pub struct Tools {
    /// "hemisphere" or "double-dome".
    pub shape: String,
    /// Double dome only: half-length of the punch's ridge along x (mm). Every radius of the
    /// tool set is then a distance from the ridge segment `|x| <= half_length`.
    pub half_length: Option<f64>,
    pub punch_radius: f64,
    pub die_opening_radius: f64,
    pub die_fillet_radius: f64,
    /// Inner radius of the blank holder (default: the die opening plus its fillet).
    pub holder_inner_radius: Option<f64>,
    /// Target edge length of the tool meshes (mm).
    pub resolution: f64,
    /// A matched die (`tools.die_shape = "matched"`): the cavity the punch fills once it has
    /// travelled this far (mm, `tools.part_depth`), with the gap `die_opening_radius -
    /// punch_radius`; `None`: the ring die with its open hole.
    pub matched_depth: Option<f64>,
}

/// Tool surfaces read from files (`shape = "files"`): STL, Gmsh `.msh` or Abaqus `.inp`, in mm,
/// placed as at the start of the stroke (stroke axis z, the blank's mid-plane at z = 0, the
/// punch below moving up, the die above, the holder below), each surface the face of its tool
/// that meets the blank.
#[derive(Clone, Debug, PartialEq)]
pub struct ToolFiles {
    pub punch: ToolFile,
    pub die: ToolFile,
    pub holder: Option<ToolFile>,
    /// Distance from the stroke axis beyond which the blank lies on the die's flat face (mm):
    /// where the wrinkle measures look. Without it they are not computed.
    pub flange_radius: Option<f64>,
}

/// A tool besides the punch, die and holder (`[[tools.extra]]`): a surface from a file on one
/// side of the blank, its friction and its motion.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtraTool {
    pub name: String,
    pub file: PathBuf,
    pub element_set: Option<String>,
    /// Coulomb friction with the blank.
    pub friction: f64,
    /// `"below"` (facing up, touching the first ply) or `"above"` (facing down, the last).
    pub blank_side: String,
    pub motion: Option<MotionTable>,
}

impl ExtraTool {
    /// Whether it lies above the blank, `key` its table in messages.
    pub fn above(&self, key: &str) -> Result<bool, String> {
        match self.blank_side.as_str() {
            "below" => Ok(false),
            "above" => Ok(true),
            other => Err(format!(
                "{key}.blank_side = \"{other}\": \"below\" (the tool under the blank, facing \
                 up) or \"above\""
            )),
        }
    }
}

/// One tool's surface: a file and, for mesh files, optionally an element set of it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolFile {
    pub file: PathBuf,
    pub element_set: Option<String>,
}

/// The `[tools]` table as written: `shape` decides which keys belong.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ToolsTable {
    shape: String,
    half_length: Option<f64>,
    punch_radius: Option<f64>,
    die_opening_radius: Option<f64>,
    die_fillet_radius: Option<f64>,
    holder_inner_radius: Option<f64>,
    resolution: Option<f64>,
    die_shape: Option<String>,
    part_depth: Option<f64>,
    #[serde(default)]
    extra: Vec<ExtraTool>,
    punch: Option<ToolTable>,
    die: Option<ToolTable>,
    holder: Option<ToolTable>,
    flange_radius: Option<f64>,
    /// Every tool's temperature in a non-isothermal run, where a tool gives none of its own.
    temperature: Option<f64>,
}

/// `tools.punch` etc. as written: a surface read from a file (with `shape = "files"`), and the
/// tool's temperature in a non-isothermal run.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ToolTable {
    file: Option<PathBuf>,
    element_set: Option<String>,
    temperature: Option<f64>,
    motion: Option<MotionTable>,
}

impl ToolTable {
    /// Whether it names a surface (a file or a set of one).
    fn names_a_surface(&self) -> bool {
        self.file.is_some() || self.element_set.is_some()
    }
}

/// The depth of a matched die (`tools.die_shape = "matched"` with `tools.part_depth`), `None`
/// for the ring die.
fn matched_depth(shape: Option<&str>, depth: Option<f64>) -> Result<Option<f64>, String> {
    match (shape.unwrap_or("ring"), depth) {
        ("ring", None) => Ok(None),
        ("ring", Some(_)) => Err(
            "tools.part_depth is the depth of a matched die: set tools.die_shape = \"matched\""
                .into(),
        ),
        ("matched", Some(d)) if d.is_finite() && d > 0.0 => Ok(Some(d)),
        ("matched", Some(d)) => Err(format!(
            "tools.part_depth = {} mm must be positive: the punch's travel when the dies close",
            shown(d)
        )),
        ("matched", None) => Err(
            "tools.part_depth (mm, the punch's travel when the dies close) is needed for \
             tools.die_shape = \"matched\""
                .into(),
        ),
        (other, _) => Err(format!(
            "tools.die_shape = \"{other}\": the dies available are \"ring\" (an open hole, the \
             default) and \"matched\" (a cavity the punch fills)"
        )),
    }
}

impl ToolsTable {
    /// The tool set, file paths resolved against `folder`; keys of the other kind of tool set
    /// are errors.
    fn resolve(self, folder: &Path) -> Result<ToolSet, String> {
        if self.shape == "files" {
            return self.files(folder).map(ToolSet::Files);
        }
        let surface = |t: &Option<ToolTable>| t.as_ref().is_some_and(ToolTable::names_a_surface);
        for (key, given) in [
            ("punch", surface(&self.punch)),
            ("die", surface(&self.die)),
            ("holder", surface(&self.holder)),
            ("flange_radius", self.flange_radius.is_some()),
        ] {
            if given {
                return Err(format!(
                    "tools.{key} is for tool surfaces read from files: set tools.shape = \"files\""
                ));
            }
        }
        let shape = self.shape;
        let need = |key: &str, v: Option<f64>| {
            v.ok_or_else(|| format!("tools.{key} is needed for tools.shape = \"{shape}\""))
        };
        Ok(ToolSet::BuiltIn(Tools {
            punch_radius: need("punch_radius", self.punch_radius)?,
            die_opening_radius: need("die_opening_radius", self.die_opening_radius)?,
            die_fillet_radius: need("die_fillet_radius", self.die_fillet_radius)?,
            resolution: need("resolution", self.resolution)?,
            half_length: self.half_length,
            holder_inner_radius: self.holder_inner_radius,
            matched_depth: matched_depth(self.die_shape.as_deref(), self.part_depth)?,
            shape,
        }))
    }

    /// The extra tools, their files resolved against `folder`, names unique and new.
    fn extra_tools(&self, folder: &Path) -> Result<Vec<ExtraTool>, String> {
        let mut tools = self.extra.clone();
        for (i, tool) in tools.iter_mut().enumerate() {
            let key = format!("tools.extra[{}]", i + 1);
            tool.above(&key)?;
            FRICTION.check(&format!("{key}.friction"), tool.friction)?;
            if ["punch", "die", "holder"].contains(&tool.name.as_str()) || tool.name.is_empty() {
                return Err(format!(
                    "{key}.name = \"{}\": give the tool a name of its own",
                    tool.name
                ));
            }
            tool.file = folder.join(&tool.file);
        }
        for (i, tool) in tools.iter().enumerate() {
            if tools[..i].iter().any(|t| t.name == tool.name) {
                return Err(format!(
                    "tools.extra[{}].name = \"{}\": another extra tool has it",
                    i + 1,
                    tool.name
                ));
            }
        }
        Ok(tools)
    }

    /// The tools' `motion` tables (punch, die, holder).
    fn motions(&self) -> [Option<MotionTable>; 3] {
        [&self.punch, &self.die, &self.holder].map(|t| t.as_ref().and_then(|t| t.motion.clone()))
    }

    /// The tools' `temperature` keys.
    fn temperatures(&self) -> ToolTemperatures {
        let of =
            |t: &Option<ToolTable>| t.as_ref().and_then(|t| t.temperature).or(self.temperature);
        ToolTemperatures {
            punch: of(&self.punch),
            die: of(&self.die),
            holder: of(&self.holder),
        }
    }

    fn files(self, folder: &Path) -> Result<ToolFiles, String> {
        let built_in_keys = [
            ("half_length", self.half_length.is_some()),
            ("die_shape", self.die_shape.is_some()),
            ("part_depth", self.part_depth.is_some()),
            ("punch_radius", self.punch_radius.is_some()),
            ("die_opening_radius", self.die_opening_radius.is_some()),
            ("die_fillet_radius", self.die_fillet_radius.is_some()),
            ("holder_inner_radius", self.holder_inner_radius.is_some()),
            ("resolution", self.resolution.is_some()),
        ];
        if let Some((key, _)) = built_in_keys.iter().find(|(_, given)| *given) {
            return Err(format!(
                "tools.{key} is for the built-in tool shapes; with tools.shape = \"files\" the \
                 tools are the surfaces of tools.punch, tools.die and tools.holder"
            ));
        }
        let need =
            |key: &str, table: Option<ToolTable>| {
                table.and_then(|t| t.file.map(|file| (file, t.element_set))).ok_or_else(|| {
                format!("tools.{key} = {{ file = \"...\" }} is needed with tools.shape = \"files\"")
            })
            };
        let at = |(file, element_set): (PathBuf, Option<String>)| ToolFile {
            file: folder.join(file),
            element_set,
        };
        let holder = match self.holder {
            Some(h) if h.names_a_surface() => Some(at(need("holder", Some(h))?)),
            _ => None,
        };
        Ok(ToolFiles {
            punch: at(need("punch", self.punch)?),
            die: at(need("die", self.die)?),
            holder,
            flange_radius: self.flange_radius,
        })
    }
}

/// Forming temperature, punch travel, blank-holder force, friction, scaling.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Process {
    /// Isothermal forming temperature (°C); in a non-isothermal run the blank's out of the
    /// oven, `blank_temperature`.
    #[serde(default = "unset")]
    pub temperature: f64,
    /// Non-isothermal run: the blank out of the oven (°C), and its time in air before the
    /// stroke (s); see [`Scenario::heat`].
    pub blank_temperature: Option<f64>,
    pub transfer_time: Option<f64>,
    /// Punch travel (mm) and physical punch speed (mm/s) of the single stroke; not given where
    /// stages or the punch's own motion table move the tools (then the punch's travel and top
    /// speed, filled in when the model is built).
    #[serde(default = "unset")]
    pub stroke: f64,
    #[serde(default = "unset")]
    pub punch_speed: f64,
    /// The press's stages, one after the other; none: the single stroke.
    #[serde(default)]
    pub stages: Vec<Stage>,
    /// Gravity (mm/s^2); standard gravity along -z where the blank hangs on springs or
    /// grippers, none otherwise.
    pub gravity: Option<[f64; 3]>,
    /// Blank-holder force (N): the holder pushes the flange against the die with it, free to
    /// move along the stroke. 0 (the default) leaves the holder out, unless a gap is given.
    #[serde(default)]
    pub blank_holder_force: f64,
    /// Instead of a force, the holder fixed at this gap (mm) below the blank's lower face: the
    /// die and the holder `thickness + gap` apart.
    pub blank_holder_gap: Option<f64>,
    /// Coulomb friction between the blank and each tool.
    pub friction: Friction,
    /// Time scaling: the stroke runs this many times faster, eta1 divided by it.
    #[serde(default = "one")]
    pub time_scaling: f64,
    /// Mass scaling to this time step (s).
    pub target_time_step: Option<f64>,
    /// `"implicit"` (the default) or `"explicit"` (docs/solver.md): the implicit solver runs
    /// the physical stroke quasi-statically, without time or mass scaling.
    #[serde(default)]
    pub solver: SolverKind,
    /// Largest increment of the implicit solver, in mm of punch travel; `None`: a sixtieth of
    /// the stroke. The output settings never change the increments.
    pub max_increment: Option<f64>,
}

fn one() -> f64 {
    1.0
}

/// A key not given: told apart from any value given.
fn unset() -> f64 {
    f64::NAN
}

/// A number key's value where given ([`unset`] where not).
fn given(value: f64) -> Option<f64> {
    (!value.is_nan()).then_some(value)
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Friction {
    pub punch: f64,
    pub die: f64,
    pub holder: f64,
}

/// What to write.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Output folder, relative to the working directory.
    #[serde(default = "default_folder")]
    pub folder: PathBuf,
    /// ParaView frames over the stroke (0: none) and rows of the CSV history.
    #[serde(default = "default_frames")]
    pub frames: usize,
    #[serde(default = "default_history")]
    pub history_points: usize,
    /// Locking angle of the fabric (degrees), marked on the shear-angle map; cells beyond it
    /// are flagged. `None`: no mark.
    pub locking_angle: Option<f64>,
    /// A line the summary prints as it is, for what the scenario's author wants every reader
    /// of its results to know (e.g. that the mesh is a coarse tutorial mesh, and by how much
    /// its force differs from a converged one).
    pub note: Option<String>,
}

impl Default for Output {
    fn default() -> Self {
        Self {
            folder: default_folder(),
            frames: default_frames(),
            history_points: default_history(),
            locking_angle: None,
            note: None,
        }
    }
}

fn default_folder() -> PathBuf {
    PathBuf::from("results")
}

fn default_frames() -> usize {
    20
}

fn default_history() -> usize {
    100
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    blank: BlankTable,
    #[serde(default)]
    boundary: Vec<Boundary>,
    tools: ToolsTable,
    process: Process,
    thermal: Option<ThermalTable>,
    #[serde(default)]
    output: Output,
    #[serde(default)]
    springs: Vec<SpringTable>,
    #[serde(default)]
    grippers: Vec<GripperTable>,
}

/// The temperature the run's once-evaluated tables are taken at: `process.temperature`, or in a
/// non-isothermal run the blank's out of the oven; one of the two, not both.
fn run_temperature(p: &Process) -> Result<f64, String> {
    match (p.temperature.is_nan(), p.blank_temperature) {
        (false, None) => Ok(p.temperature),
        (true, Some(t)) => Ok(t),
        (false, Some(_)) => Err(
            "process.temperature (an isothermal run) and process.blank_temperature (a \
             non-isothermal one) exclude each other: give one"
                .into(),
        ),
        (true, None) => Err(
            "process.temperature is needed: the forming temperature of an isothermal run (°C), \
             or process.blank_temperature for a non-isothermal one"
                .into(),
        ),
    }
}

/// Why a scenario cannot be used: the file and what is wrong (with the key or the line).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{origin}: {message}")]
pub struct ScenarioError {
    pub origin: String,
    pub message: String,
}

impl Scenario {
    /// Reads `path`, applies the `key=value` overrides, and checks it.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Self, ScenarioError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError {
            origin: origin.clone(),
            message: format!("cannot read the scenario: {e}"),
        })?;
        let folder = path.parent().unwrap_or(Path::new("."));
        Self::from_text(&text, &origin, folder, overrides)
    }

    /// The scenario written in `text` (named `origin` in messages, its file paths relative to
    /// `folder`) with the `key=value` overrides applied, checked as [`Self::load`] checks a
    /// file: the same messages, naming the key.
    pub fn from_text(
        text: &str,
        origin: &str,
        folder: &Path,
        overrides: &[String],
    ) -> Result<Self, ScenarioError> {
        let error = |message: String| ScenarioError {
            origin: origin.to_string(),
            message,
        };
        let file: ScenarioFile = if overrides.is_empty() {
            from_toml_text(text).map_err(error)?
        } else {
            let table = overridden_table(text, overrides).map_err(error)?;
            from_toml_value(toml::Value::Table(table))
                .map_err(|e| error(format!("{e} (with --set {})", overrides.join(" --set "))))?
        };
        let mut process = file.process;
        process.temperature = run_temperature(&process).map_err(error)?;
        let has_holder = process.blank_holder_force > 0.0 || process.blank_holder_gap.is_some();
        let heat = heat_scenario(
            process.blank_temperature,
            process.transfer_time,
            file.tools.temperatures(),
            file.thermal,
            has_holder,
        )
        .map_err(error)?;
        let motions = file.tools.motions();
        let extra_tools = file.tools.extra_tools(folder).map_err(error)?;
        let scenario = Scenario {
            origin: origin.to_string(),
            blank: file
                .blank
                .resolve(folder, process.temperature)
                .map_err(error)?,
            boundary: file.boundary,
            tools: file.tools.resolve(folder).map_err(error)?,
            motions,
            extra_tools,
            supports: SupportScenario {
                springs: file.springs,
                grippers: file.grippers,
                gravity: process.gravity,
            },
            process,
            output: file.output,
            heat,
        };
        scenario.check().map_err(error)?;
        Ok(scenario)
    }

    /// The scenario at `path` with the `key=value` overrides applied and its file paths (the
    /// card, a blank mesh, tool files) made absolute, as TOML text: a scenario that runs from
    /// any folder, such as a study's case folder. Checked by loading it as [`Self::load`] does.
    pub fn standalone_text(path: &Path, overrides: &[String]) -> Result<String, ScenarioError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError {
            origin: origin.clone(),
            message: format!("cannot read the scenario: {e}"),
        })?;
        let folder = path.parent().unwrap_or(Path::new("."));
        Self::standalone_from_text(&text, &origin, folder, overrides)
    }

    /// [`Self::standalone_text`] of a scenario written in `text`, its paths relative to
    /// `folder`.
    pub fn standalone_from_text(
        text: &str,
        origin: &str,
        folder: &Path,
        overrides: &[String],
    ) -> Result<String, ScenarioError> {
        let error = |message: String| ScenarioError {
            origin: origin.to_string(),
            message,
        };
        Self::from_text(text, origin, folder, overrides)?;
        let mut table = overridden_table(text, overrides).map_err(error)?;
        let folder = std::path::absolute(folder).map_err(|e| error(e.to_string()))?;
        for keys in [
            &["blank", "card"][..],
            &["blank", "mesh"],
            &["tools", "punch", "file"],
            &["tools", "die", "file"],
            &["tools", "holder", "file"],
        ] {
            make_absolute(&mut table, keys, &folder);
        }
        let extras = table
            .get_mut("tools")
            .and_then(|t| t.get_mut("extra"))
            .and_then(toml::Value::as_array_mut);
        for extra in extras.into_iter().flatten() {
            if let Some(extra) = extra.as_table_mut() {
                make_absolute(extra, &["file"], &folder);
            }
        }
        let plies = table
            .get_mut("blank")
            .and_then(|b| b.get_mut("plies"))
            .and_then(toml::Value::as_array_mut);
        for ply in plies.into_iter().flatten() {
            if let Some(ply) = ply.as_table_mut() {
                make_absolute(ply, &["card"], &folder);
                make_absolute(ply, &["mesh"], &folder);
            }
        }
        toml::to_string(&table).map_err(|e| error(e.to_string()))
    }

    /// The built-in tool set, or an error naming what needs it (`what`).
    pub fn built_in_tools(&self, what: &str) -> Result<&Tools, String> {
        match &self.tools {
            ToolSet::BuiltIn(t) => Ok(t),
            ToolSet::Files(_) => Err(format!(
                "{what} needs a built-in tool shape (tools.shape = \"hemisphere\" or \
                 \"double-dome\"), not tools read from files"
            )),
        }
    }

    /// Half-length of the punch's ridge (mm): 0 for the hemisphere and for tool files (whose
    /// measures are taken about the stroke axis).
    pub fn ridge_half_length(&self) -> f64 {
        match &self.tools {
            ToolSet::BuiltIn(t) => t.ridge_half_length(),
            ToolSet::Files(_) => 0.0,
        }
    }

    /// Distance (mm) of `(x, y)` from the punch's axis (hemisphere) or ridge (double dome):
    /// the radius that every size of the tool set is measured along.
    pub fn distance_from_ridge(&self, x: f64, y: f64) -> f64 {
        crate::contact::distance_from_ridge(self.ridge_half_length(), x, y)
    }

    /// Whether the blank-holder is in the run (a force or a gap drives it).
    pub fn has_holder(&self) -> bool {
        self.process.blank_holder_force > 0.0 || self.process.blank_holder_gap.is_some()
    }

    /// Consistency: sizes positive, the punch passes through the die opening, the blank
    /// reaches over the holder, the stroke stays within the die. Checks that need the meshes
    /// (a blank or tools read from files) are made when the model is built.
    fn check(&self) -> Result<(), String> {
        self.check_ranges()?;
        self.check_process()?;
        check_note(self.output.note.as_deref())?;
        match &self.tools {
            ToolSet::BuiltIn(t) => self.check_built_in_tools(t)?,
            ToolSet::Files(f) => {
                if self.has_holder() && f.holder.is_none() {
                    return Err(
                        "process.blank_holder_force or blank_holder_gap needs a holder: give \
                         tools.holder = { file = \"...\" }"
                            .into(),
                    );
                }
            }
        }
        for boundary in &self.boundary {
            boundary.set()?;
            boundary.mask()?;
        }
        Ok(())
    }

    /// Every number of the scenario inside the range of its quantity (`crate::limits`, listed
    /// in docs/forming.md), the first outside named by its key.
    fn check_ranges(&self) -> Result<(), String> {
        let (p, o) = (&self.process, &self.output);
        let mut given = vec![
            ("blank.ply_angle", Some(self.blank.ply_angle), ANGLE),
            ("process.temperature", Some(p.temperature), TEMPERATURE),
            ("process.stroke", given(p.stroke), LENGTH),
            ("process.punch_speed", given(p.punch_speed), SPEED),
            (
                "process.blank_holder_force",
                Some(p.blank_holder_force),
                FORCE,
            ),
            ("process.blank_holder_gap", p.blank_holder_gap, GAP),
            ("process.friction.punch", Some(p.friction.punch), FRICTION),
            ("process.friction.die", Some(p.friction.die), FRICTION),
            ("process.friction.holder", Some(p.friction.holder), FRICTION),
            ("process.time_scaling", Some(p.time_scaling), TIME_SCALING),
            ("process.target_time_step", p.target_time_step, TIME_STEP),
            ("process.max_increment", p.max_increment, LENGTH),
            ("output.frames", Some(o.frames as f64), FRAMES),
            (
                "output.history_points",
                Some(o.history_points as f64),
                HISTORY_POINTS,
            ),
            ("output.locking_angle", o.locking_angle, SHEAR_ANGLE),
        ];
        if let BlankShape::Rectangle {
            width,
            length,
            element_size,
            ..
        } = self.blank.shape
        {
            given.extend([
                ("blank.width", Some(width), LENGTH),
                ("blank.length", Some(length), LENGTH),
                ("blank.element_size", Some(element_size), LENGTH),
            ]);
        }
        match &self.tools {
            ToolSet::BuiltIn(t) => given.extend([
                ("tools.half_length", t.half_length, LENGTH),
                ("tools.punch_radius", Some(t.punch_radius), LENGTH),
                (
                    "tools.die_opening_radius",
                    Some(t.die_opening_radius),
                    LENGTH,
                ),
                ("tools.die_fillet_radius", Some(t.die_fillet_radius), LENGTH),
                ("tools.holder_inner_radius", t.holder_inner_radius, LENGTH),
                ("tools.resolution", Some(t.resolution), LENGTH),
                ("tools.part_depth", t.matched_depth, LENGTH),
            ]),
            ToolSet::Files(f) => given.push(("tools.flange_radius", f.flange_radius, LENGTH)),
        }
        check_given(given)?;
        self.check_layup_ranges()
    }

    /// The layup's angles within their range, each named by its key.
    fn check_layup_ranges(&self) -> Result<(), String> {
        let Some(layup) = &self.blank.layup else {
            return Ok(());
        };
        for (i, ply) in layup.plies.iter().enumerate() {
            let key = match layup.from_angles {
                true => format!("blank.ply_angles[{}]", i + 1),
                false => format!("blank.plies[{}].angle", i + 1),
            };
            ANGLE.check(&key, ply.angle)?;
            if let Some(BlankShape::Rectangle { width, length, .. }) = ply.shape {
                LENGTH.check(&format!("blank.plies[{}].width", i + 1), width)?;
                LENGTH.check(&format!("blank.plies[{}].length", i + 1), length)?;
            }
        }
        // the film's values are checked as they are read, at the run's temperature
        // (InterplyTable::friction)
        Ok(())
    }

    /// Whether stages or the punch's own motion table move the punch, not the single stroke.
    pub fn moves_by_paths(&self) -> bool {
        let punch_path = self.motions[0]
            .as_ref()
            .is_some_and(|m| m.displacement.is_some() || m.speed.is_some());
        !self.process.stages.is_empty() || punch_path
    }

    /// `process.stroke` and `punch_speed` for the single stroke, and only for it.
    fn check_stroke_keys(&self) -> Result<(), String> {
        let p = &self.process;
        for (key, value) in [
            ("process.stroke", p.stroke),
            ("process.punch_speed", p.punch_speed),
        ] {
            match (self.moves_by_paths(), value.is_nan()) {
                (true, false) => {
                    return Err(format!(
                        "{key} is for the single stroke; here process.stages (or                          tools.punch.motion) move the punch: leave {key} out"
                    ))
                }
                (false, true) => {
                    return Err(format!(
                        "{key} is needed (or process.stages, or tools.punch.motion, to move                          the tools)"
                    ))
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn check_process(&self) -> Result<(), String> {
        self.check_stroke_keys()?;
        let p = &self.process;
        if p.solver == SolverKind::Implicit {
            let explicit_only = [
                ("process.time_scaling", p.time_scaling != 1.0),
                ("process.target_time_step", p.target_time_step.is_some()),
            ];
            if let Some((key, _)) = explicit_only.iter().find(|(_, set)| *set) {
                return Err(format!(
                    "{key} is only used by the explicit solver; the implicit solver (the \
                     default where process.solver is not given) runs the stroke at the physical \
                     speed without inertia: leave {key} out, or set process.solver = \
                     \"explicit\""
                ));
            }
        } else if p.max_increment.is_some() {
            return Err(
                "process.max_increment is only used by the implicit solver (the explicit \
                 solver's steps are its stable time step): leave it out or set process.solver \
                 = \"implicit\""
                    .into(),
            );
        }
        if p.blank_holder_gap.is_some() && p.blank_holder_force > 0.0 {
            return Err(
                "process.blank_holder_force and process.blank_holder_gap are two ways to drive \
                 the holder: give one of them"
                    .into(),
            );
        }
        if let Some(travel) = p.max_increment {
            if travel > p.stroke {
                return Err(format!(
                    "process.max_increment = {travel} mm exceeds the stroke, {} mm",
                    p.stroke
                ));
            }
        }
        Ok(())
    }

    fn check_built_in_tools(&self, t: &Tools) -> Result<(), String> {
        t.check_shape()?;
        if t.die_opening_radius <= t.punch_radius {
            return Err(format!(
                "tools.die_opening_radius = {} must exceed tools.punch_radius = {} (plus the \
                 blank's thickness) for the punch to pass",
                shown_apart(t.die_opening_radius, t.punch_radius),
                shown(t.punch_radius)
            ));
        }
        let p = &self.process;
        let punch_height = 2.0 * t.punch_radius;
        if let Some(depth) = t.matched_depth.filter(|d| *d > punch_height) {
            return Err(format!(
                "tools.part_depth = {} mm goes beyond the punch (radius {} mm with a skirt as \
                 tall: {} mm of travel at most)",
                shown_apart(depth, punch_height),
                shown(t.punch_radius),
                shown(punch_height)
            ));
        }
        if p.stroke > punch_height {
            return Err(format!(
                "process.stroke = {} mm goes beyond the punch (radius {} mm with a skirt as tall: \
                 {} mm of stroke at most)",
                shown_apart(p.stroke, punch_height),
                shown(t.punch_radius),
                shown(punch_height)
            ));
        }
        let holder = t.holder_inner_radius();
        if holder <= t.punch_radius {
            return Err(format!(
                "tools.holder_inner_radius = {} must exceed tools.punch_radius = {}",
                shown_apart(holder, t.punch_radius),
                shown(t.punch_radius)
            ));
        }
        if let BlankShape::Rectangle {
            width,
            length,
            element_size,
            ..
        } = self.blank.shape
        {
            let half_side = (0.5 * width - t.ridge_half_length()).min(0.5 * length);
            if self.has_holder() && half_side <= holder {
                return Err(format!(
                    "the blank ({} x {} mm) reaches {} mm from the punch's axis (ridge), not \
                     over the blank holder (inner radius {} mm): it cannot be held",
                    shown(width),
                    shown(length),
                    shown_apart(half_side, holder),
                    shown(holder)
                ));
            }
            t.check_element_size(element_size, "blank.element_size")?;
        }
        Ok(())
    }
}

impl Tools {
    /// Half-length of the punch's ridge (mm): 0 for the hemisphere.
    pub fn ridge_half_length(&self) -> f64 {
        self.half_length.unwrap_or(0.0)
    }

    /// The holder's inner radius.
    pub fn holder_inner_radius(&self) -> f64 {
        self.holder_inner_radius
            .unwrap_or(self.die_opening_radius + self.die_fillet_radius)
    }

    /// At least four elements of `size` across the punch radius; `what` names the size.
    pub fn check_element_size(&self, size: f64, what: &str) -> Result<(), String> {
        let largest = 0.25 * self.punch_radius;
        if size > largest {
            return Err(format!(
                "{what} = {} mm is too coarse for a punch of radius {} mm: at least four \
                 elements across the punch radius are needed, {} mm at most",
                shown_apart(size, largest),
                shown(self.punch_radius),
                shown(largest)
            ));
        }
        Ok(())
    }

    /// The shape is known, and the ridge's half-length given exactly when it has one.
    fn check_shape(&self) -> Result<(), String> {
        match (self.shape.as_str(), self.half_length) {
            ("hemisphere", None) => Ok(()),
            ("hemisphere", Some(_)) => Err(
                "tools.half_length is for tools.shape = \"double-dome\"; a hemisphere has none"
                    .into(),
            ),
            ("double-dome", Some(_)) => Ok(()),
            ("double-dome", None) => Err(
                "tools.half_length (the half-length of the ridge, mm) is needed for tools.shape \
                 = \"double-dome\""
                    .into(),
            ),
            (other, _) => Err(format!(
                "tools.shape = \"{other}\": the tool sets available are \"hemisphere\", \
                 \"double-dome\" and \"files\""
            )),
        }
    }
}

/// `section.key=value` (any depth): sets an existing or new scalar; the value is read as TOML
/// (a number, a quoted string, true/false, a list), a bare word as a string. A key may name an
/// existing element of a list by its place from 1, `blank.ply_angles[2]` or
/// `blank.plies[2].angle`: any ply's key can be set, and swept.
fn apply_override(table: &mut toml::Table, assignment: &str) -> Result<(), String> {
    let (path, raw) = assignment
        .split_once('=')
        .ok_or_else(|| format!("--set {assignment}: expected key=value"))?;
    let keys: Vec<&str> = path.trim().split('.').collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(format!("--set {assignment}: empty key in '{path}'"));
    }
    let mut value = parse_scalar(raw.trim());
    let (last, parents) = keys.split_last().unwrap_or((&"", &[]));
    let mut here = table;
    for key in parents {
        let (name, index) = indexed(key).map_err(|e| format!("--set {assignment}: {e}"))?;
        let entry = match index {
            None => here
                .entry(name.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new())),
            Some(i) => element(here, name, i).map_err(|e| format!("--set {assignment}: {e}"))?,
        };
        here = entry
            .as_table_mut()
            .ok_or_else(|| format!("--set {assignment}: '{key}' is not a section"))?;
    }
    let (name, index) = indexed(last).map_err(|e| format!("--set {assignment}: {e}"))?;
    let slot = match index {
        Some(i) => element(here, name, i).map_err(|e| format!("--set {assignment}: {e}"))?,
        None => here
            .entry(name.to_string())
            .or_insert_with(|| value.clone()),
    };
    // `--set process.temperature=310` on a float key means 310.0
    if let (toml::Value::Float(_), toml::Value::Integer(i)) = (&*slot, &value) {
        value = toml::Value::Float(*i as f64);
    }
    if matches!(slot, toml::Value::Table(_)) {
        return Err(format!(
            "--set {assignment}: '{path}' is a section, not a value"
        ));
    }
    *slot = value;
    Ok(())
}

/// A key's name and the place (from 1) it gives in brackets, `ply_angles[2]`, if any.
fn indexed(key: &str) -> Result<(&str, Option<usize>), String> {
    let Some((name, rest)) = key.split_once('[') else {
        return Ok((key, None));
    };
    let place = rest
        .strip_suffix(']')
        .and_then(|i| i.parse::<usize>().ok())
        .filter(|&i| i >= 1)
        .ok_or_else(|| format!("'{key}': a list's element is named by its place from 1, [1]"))?;
    Ok((name, Some(place)))
}

/// Element `place` (from 1) of the list `name` of `table`, which must have it.
fn element<'t>(
    table: &'t mut toml::Table,
    name: &str,
    place: usize,
) -> Result<&'t mut toml::Value, String> {
    let list = match table.get_mut(name) {
        Some(toml::Value::Array(list)) => list,
        _ => return Err(format!("'{name}' is not a list of the scenario")),
    };
    let length = list.len();
    list.get_mut(place - 1)
        .ok_or_else(|| format!("'{name}[{place}]': the list has {length} elements"))
}

/// The scenario `text` as a TOML table with the `key=value` overrides applied.
fn overridden_table(text: &str, overrides: &[String]) -> Result<toml::Table, String> {
    let mut table: toml::Table = from_toml_text(text)?;
    for o in overrides {
        apply_override(&mut table, o)?;
    }
    Ok(table)
}

/// The string at the path `keys` of `table`, if any, joined to `folder` (an absolute path stays
/// as it is).
fn make_absolute(table: &mut toml::Table, keys: &[&str], folder: &Path) {
    let (last, parents) = keys.split_last().unwrap_or((&"", &[]));
    let mut here = table;
    for key in parents {
        match here.get_mut(*key).and_then(toml::Value::as_table_mut) {
            Some(t) => here = t,
            None => return,
        }
    }
    if let Some(toml::Value::String(s)) = here.get_mut(*last) {
        *s = folder.join(&*s).display().to_string();
    }
}

fn parse_scalar(raw: &str) -> toml::Value {
    let wrapped = format!("v = {raw}");
    toml::from_str::<toml::Table>(&wrapped)
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(raw.to_string()))
}

/// `output.note` is one line of at most [`NOTE_LENGTH`] characters, not blank: the summary
/// prints it as a row of its table.
fn check_note(note: Option<&str>) -> Result<(), String> {
    match note {
        Some(n)
            if n.trim().is_empty()
                || n.contains(['\n', '\r'])
                || n.chars().count() > NOTE_LENGTH =>
        {
            Err(format!(
                "output.note: one line of 1 to {NOTE_LENGTH} characters, printed in the summary"
            ))
        }
        _ => Ok(()),
    }
}

/// The longest `output.note`, in characters.
const NOTE_LENGTH: usize = 300;

#[cfg(test)]
mod tests {
    use super::*;

    /// A note is one line the summary can print; a blank one, one of several lines or one
    /// longer than a screen's worth is refused with its key.
    #[test]
    fn a_note_is_one_line() {
        assert!(check_note(None).is_ok());
        assert!(check_note(Some("coarse tutorial mesh: the force is 5 % high")).is_ok());
        for bad in ["", "  ", "two\nlines", &"x".repeat(NOTE_LENGTH + 1)] {
            let e = check_note(Some(bad)).unwrap_err();
            assert!(e.starts_with("output.note:"), "{e}");
        }
    }

    fn interply(text: &str) -> InterplyTable {
        toml::from_str(text).unwrap()
    }

    /// A table gives its values at its temperatures and the straight line between them halfway;
    /// a number is the same at any temperature.
    #[test]
    fn interply_tables_interpolate_at_the_run_temperature() {
        let table = interply(
            "friction = [[280.0, 0.3], [320.0, 0.2]]\n\
             film_viscosity = [[280.0, 294.0], [300.0, 186.0], [320.0, 122.0]]\n\
             film_thickness = 0.01\n\
             yield_stress = [[280.0, 0.12], [320.0, 0.08]]\n",
        );
        let at = |t: f64| table.friction("blank.interply", t).unwrap();
        assert_eq!(at(280.0).coulomb, 0.3);
        assert_eq!(at(320.0).shear_cap, 0.08);
        assert_eq!(at(300.0).film, 1e-6 * 186.0 / 0.01);
        let mid = at(300.0);
        assert!((mid.coulomb - 0.25).abs() < 1e-15 && (mid.shear_cap - 0.1).abs() < 1e-15);
        let eta = at(310.0).film * 0.01 / 1e-6;
        assert!(
            (eta - 154.0).abs() < 1e-9,
            "{eta} Pa·s halfway from 186 to 122"
        );
        let number = interply("friction = 0.2\n");
        assert_eq!(
            number.friction("blank.interply", -50.0).unwrap(),
            FilmFriction::coulomb(0.2)
        );
        assert_eq!(
            number.friction("blank.interply", 900.0).unwrap(),
            FilmFriction::coulomb(0.2)
        );
    }

    /// The shear-thinning laws read from their keys, in the model's units.
    #[test]
    fn interply_film_laws_are_read_in_the_models_units() {
        let cross = interply(
            "friction = 0.2\nfilm_law = \"cross\"\nfilm_viscosity = 186.0\n\
             film_thickness = 0.01\nfilm_index = 0.4\nfilm_transition_stress = 0.02\n",
        );
        assert_eq!(
            cross.friction("blank.interply", 300.0).unwrap(),
            FilmFriction::cross(0.2, (186e-6, 0.4, 0.02), 0.01, f64::INFINITY)
        );
        let power = interply(
            "friction = 0.2\nfilm_law = \"power-law\"\nfilm_consistency = 3100.0\n\
             film_thickness = 0.01\nfilm_index = 0.4\nyield_stress = 0.1\n",
        );
        assert_eq!(
            power.friction("blank.interply", 300.0).unwrap(),
            FilmFriction::power_law(0.2, (3.1e-3, 0.4, DEFAULT_CUTOFF_RATE), 0.01, 0.1)
        );
    }

    /// Tables outside the run's temperature or not increasing, values out of range and keys
    /// of another law are refused, naming the key.
    #[test]
    fn bad_interply_values_are_refused_naming_the_key() {
        let cases = [
            (
                "friction = [[310.0, 0.2], [320.0, 0.3]]",
                "blank.interply.friction is given from 310 to 320 °C, and process.temperature \
                 = 300 °C lies outside",
            ),
            (
                "friction = [[300.0, 0.2], [280.0, 0.3]]",
                "temperatures of blank.interply.friction must increase strictly",
            ),
            (
                "friction = [[280.0, 0.2], [320.0, 7.0]]",
                "blank.interply.friction (pair 2, at 320 °C) = 7 is out of range",
            ),
            ("friction = []", "blank.interply.friction is empty"),
            (
                "friction = 0.2\nyield_stress = [[280.0, 0.1], [2000.0, 0.1]]",
                "blank.interply.yield_stress (pair 2, its temperature) = 2000 °C",
            ),
            (
                "friction = 0.2\nfilm_index = 0.4",
                "blank.interply.film_index is not a key of a Newtonian film",
            ),
            (
                "friction = 0.2\nfilm_law = \"cross\"\nfilm_thickness = 0.01",
                "blank.interply.film_viscosity is needed by film_law = \"cross\"",
            ),
            (
                "friction = 0.2\nfilm_law = \"power-law\"\nfilm_viscosity = 100.0",
                "blank.interply.film_viscosity is not a key of film_law = \"power-law\"",
            ),
            (
                "friction = 0.2\nfilm_law = \"power-law\"\nfilm_consistency = 3e3\n\
                 film_thickness = 0.01\nfilm_index = 1.5",
                "blank.interply.film_index = 1.5 is out of range",
            ),
            (
                "friction = 0.2\nfilm_viscosity = 100.0\nfilm_thickness = 0.0",
                "blank.interply.film_thickness = 0 mm is out of range",
            ),
        ];
        for (text, expected) in cases {
            let e = interply(text)
                .friction("blank.interply", 300.0)
                .unwrap_err();
            assert!(e.contains(expected), "{text}: {e}");
        }
    }

    /// The `[blank]` table of `text` resolved at 300 °C: its layup's friction per pair.
    fn pair_friction(text: &str) -> Result<Vec<FilmFriction>, String> {
        let blank: BlankTable = toml::from_str(text).unwrap();
        let blank = blank.resolve(Path::new("."), 300.0)?;
        Ok(blank.layup.unwrap().interfaces)
    }

    const FOUR_PLIES: &str = "card = \"c.toml\"\nwidth = 1.0\nlength = 1.0\n\
                              element_size = 1.0\n\
                              [[plies]]\nangle = 0.0\n[[plies]]\nangle = 45.0\nname = \"core\"\n\
                              [[plies]]\nangle = 45.0\n[[plies]]\nangle = 0.0\n";

    /// `[[blank.interfaces]]` gives a pair, by places or names in either order, its own law;
    /// the other pairs keep `blank.interply`'s, which may be left out once every pair has one.
    #[test]
    fn an_interface_table_overrides_the_layups_friction_for_its_pair() {
        let text = format!(
            "{FOUR_PLIES}[interply]\nfriction = 0.2\n\
             [[interfaces]]\nbetween = [3, \"core\"]\nfriction = 0.5\n\
             [[interfaces]]\nbetween = [3, 4]\nfriction = 0.1\nfilm_viscosity = 100.0\n\
             film_thickness = 0.01\n"
        );
        let pairs = pair_friction(&text).unwrap();
        assert_eq!(
            pairs,
            [
                FilmFriction::coulomb(0.2),
                FilmFriction::coulomb(0.5),
                FilmFriction::newtonian(0.1, 1e-6 * 100.0 / 0.01, f64::INFINITY),
            ]
        );
        let every = format!(
            "{FOUR_PLIES}[[interfaces]]\nbetween = [1, 2]\nfriction = 0.3\n\
             [[interfaces]]\nbetween = [2, 3]\nfriction = 0.3\n\
             [[interfaces]]\nbetween = [4, 3]\nfriction = 0.3\n"
        );
        assert_eq!(
            pair_friction(&every).unwrap(),
            [FilmFriction::coulomb(0.3); 3]
        );
    }

    /// An interface naming a ply the layup lacks, two plies not next to each other, a pair
    /// twice, or no pair at all is refused naming the table; so is a layup with pairs left
    /// without friction.
    #[test]
    fn bad_interface_tables_are_refused_naming_the_key() {
        let cases = [
            (
                "between = [4, 5]\nfriction = 0.1",
                "blank.interfaces[1].between names ply 5",
            ),
            ("between = [0, 1]\nfriction = 0.1", "names ply 0"),
            (
                "between = [\"skin\", 2]\nfriction = 0.1",
                "\"skin\" is not one of",
            ),
            ("between = [1, 3]\nfriction = 0.1", "neighbouring"),
            ("friction = 0.1", "blank.interfaces[1].between is needed"),
            (
                "between = [1, 2]\nfriction = 0.1\n[[interfaces]]\nbetween = [2, 1]\n\
                 friction = 0.1",
                "blank.interfaces[2].between: plies 1 and 2 have a table before it",
            ),
            (
                "between = [1, 2]\nfriction = -0.1",
                "blank.interfaces[1].friction",
            ),
            (
                "between = [1, 2]\nfriction = 0.1\nfilm_index = 0.5",
                "blank.interfaces[1].film_index is not a key",
            ),
        ];
        for (table, expected) in cases {
            let text = format!("{FOUR_PLIES}[interply]\nfriction = 0.2\n[[interfaces]]\n{table}\n");
            let e = pair_friction(&text).unwrap_err();
            assert!(e.contains(expected), "{table}: {e}");
        }
        let partial = format!("{FOUR_PLIES}[[interfaces]]\nbetween = [1, 2]\nfriction = 0.1\n");
        let e = pair_friction(&partial).unwrap_err();
        assert!(e.contains("a layup needs blank.interply.friction"), "{e}");
        let between = format!("{FOUR_PLIES}[interply]\nfriction = 0.2\nbetween = [1, 2]\n");
        let e = pair_friction(&between).unwrap_err();
        assert!(e.contains("blank.interply.between is not a key"), "{e}");
    }

    #[test]
    fn overrides_set_nested_scalars_and_refuse_sections() {
        let mut table: toml::Table = toml::from_str("[process]\ntemperature = 300.0\n").unwrap();
        apply_override(&mut table, "process.temperature=310").unwrap();
        assert_eq!(table["process"]["temperature"], toml::Value::Float(310.0));
        apply_override(&mut table, "output.folder=out").unwrap();
        assert_eq!(table["output"]["folder"], toml::Value::String("out".into()));
        assert!(apply_override(&mut table, "process=3").is_err());
        assert!(apply_override(&mut table, "process.temperature").is_err());
        assert!(apply_override(&mut table, "process..x=1").is_err());
    }

    #[test]
    fn overrides_reach_an_element_of_a_list() {
        let text = "[blank]\nply_angles = [0.0, 45.0]\n[[blank.plies]]\nangle = 0.0\n";
        let mut table: toml::Table = toml::from_str(text).unwrap();
        apply_override(&mut table, "blank.ply_angles[2]=30").unwrap();
        let angles = table["blank"]["ply_angles"].as_array().unwrap();
        assert_eq!(angles[1], toml::Value::Float(30.0));
        assert_eq!(angles[0], toml::Value::Float(0.0));
        apply_override(&mut table, "blank.plies[1].angle=15").unwrap();
        assert_eq!(
            table["blank"]["plies"][0]["angle"],
            toml::Value::Float(15.0)
        );
        for bad in [
            "blank.ply_angles[3]=1",
            "blank.ply_angles[0]=1",
            "blank.ply_angles[x]=1",
            "blank.width[1]=1",
            "blank.plies[2].angle=1",
        ] {
            let e = apply_override(&mut table, bad).unwrap_err();
            assert!(e.contains(bad), "{e}");
        }
    }
}
