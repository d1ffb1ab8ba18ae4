//! The standard rigid tools of a hemispherical (and double-dome) thermo-stamping set-up, as
//! triangulated surfaces oriented towards the blank.
//!
//! # Conventions
//!
//! - The stroke axis is `z`. The blank lies initially in the plane `z = 0`, centred on the axis.
//! - The **punch** is below the blank (`z <= 0`) and moves up (`+z`); its apex touches `z = 0`.
//! - The **die** is above the blank (`z >= 0`): its flat underside lies in `z = 0` and its hole
//!   goes up, so the punch pushes the blank into it. A *matched* die instead closes on the
//!   punch: a cavity the punch fills with a uniform gap at the end of its stroke.
//! - The **blank holder** is below the blank, around the punch: a flat annulus in `z = 0`.
//! - Every surface is placed touching the blank's *mid-plane*; the forming driver translates the
//!   tools by half the blank thickness (and the clearance) before a run.
//! - As everywhere in [`super::surface`], triangles are counter-clockwise seen from the blank, so
//!   the normal `(b - a) x (c - a)` points towards the blank: up and outward on the punch, down
//!   and into the hole on the die, up on the blank holder. Surfaces are open (no bottom or top
//!   lids): only the side the blank can touch is meshed.
//!
//! # Meshes
//!
//! Every tool is a *profile* `(r, z)` in a meridian half-plane swept around the axis (or, for the
//! double dome, around a segment of the `x` axis). Each profile point becomes a ring of vertices;
//! neighbouring rings are stitched into triangles by walking both rings in angle order, so rings
//! may have different numbers of vertices (the number follows the ring's circumference). The
//! target edge length is `resolution` (mm), both along the profile and around the rings, with two
//! (choice)s to keep coarse meshes round: a circular arc is cut into steps of at most 15°, and a
//! full ring has at least 12 segments.
//!
//! Every vertex lies exactly (to rounding) on the analytic surface, so the faceting error in
//! area and volume is second order in `resolution`.

use super::surface::TriangleSurface;
use super::swept_profile::{ProfilePiece, SweptProfile};
use nalgebra::Vector3;
use std::f64::consts::{FRAC_PI_2, PI};

/// Largest angle (rad) of one step along a circular arc of the profile: 15°.
const MAX_ARC_STEP: f64 = PI / 12.0;
/// Fewest segments on a half ring (a full circle gets at least twice this).
const MIN_HALF_RING_SEGMENTS: usize = 6;
/// Most segments on one piece of profile or ring: a guard against absurd `resolution`s.
const MAX_SEGMENTS: f64 = 1.0e6;
/// Most vertices of one tool: a guard against running out of memory.
const MAX_VERTICES: f64 = 5.0e6;
/// Ring parameter period: the four pieces of a ring (right half circle, top straight, left half
/// circle, bottom straight) each span one unit.
const RING_PERIOD: f64 = 4.0;

/// Hemispherical punch of radius `radius` with a vertical cylindrical skirt of height `radius`
/// below the equator, so the punch reaches from `z = -2 radius` up to its apex at the origin.
///
/// The skirt height is a (choice): a stroke deeper than the punch radius draws the blank along
/// the cylinder, and a skirt as tall as the radius covers any stroke a hemispherical die allows.
/// Use [`hemisphere_punch_with_skirt`] for another height.
pub fn hemisphere_punch(radius: f64, resolution: f64) -> Result<TriangleSurface, String> {
    hemisphere_punch_with_skirt(radius, radius, resolution)
}

/// Hemispherical punch: the cap `|x - c| = radius`, `z >= -radius`, with centre
/// `c = (0, 0, -radius)` (apex at the origin), continued below its equator by a vertical cylinder
/// of radius `radius` down to `z = -radius - skirt_height`. `skirt_height = 0` gives the bare cap.
/// Normals point outward, away from the centre, towards the blank.
pub fn hemisphere_punch_with_skirt(
    radius: f64,
    skirt_height: f64,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    let shape = punch_shape("hemisphere_punch", 0.0, radius, skirt_height)?;
    triangulated("hemisphere_punch", &shape, resolution)
}

/// Die of a hemispherical set-up: a flat annular plate in `z = 0` (normal down, towards the
/// blank) from `outer_radius` in to `opening_radius + fillet_radius`, a torus fillet of radius
/// `fillet_radius` (centre circle at `r = opening_radius + fillet_radius`, `z = fillet_radius`)
/// turning through 90° into a vertical cylindrical hole wall of radius `opening_radius` that goes
/// up to `z = depth`. Normals point down on the plate and into the hole on the fillet and wall.
///
/// The fillet is tangent to the plate and to the wall, so the surface is C1 (tangent-continuous).
pub fn hemisphere_die(
    opening_radius: f64,
    fillet_radius: f64,
    outer_radius: f64,
    depth: f64,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    let die = DieShape {
        opening_radius,
        fillet_radius,
        outer_radius,
        depth,
    };
    stadium_die("hemisphere_die", 0.0, &die, resolution)
}

/// The sizes of a die's profile: see [`hemisphere_die`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DieShape {
    pub opening_radius: f64,
    pub fillet_radius: f64,
    pub outer_radius: f64,
    pub depth: f64,
}

/// Die of the double-dome set-up: the profile of [`hemisphere_die`] swept around the ridge
/// segment `|x| <= half_length`, `y = 0` of [`double_dome_punch`], so that every distance of
/// the hemisphere die from its axis becomes a distance from the ridge: a stadium-shaped
/// opening of radius `opening_radius` about the ridge, its fillet, and a plate out to
/// `outer_radius` from the ridge. `half_length = 0` gives [`hemisphere_die`].
pub fn double_dome_die(
    half_length: f64,
    die: &DieShape,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    stadium_die("double_dome_die", half_length, die, resolution)
}

fn stadium_die(
    tool: &str,
    half_length: f64,
    die: &DieShape,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    triangulated(tool, &die_shape(tool, half_length, die)?, resolution)
}

/// The exact surface of [`double_dome_die`] (of [`hemisphere_die`] for `half_length = 0`).
pub fn double_dome_die_shape(half_length: f64, die: &DieShape) -> Result<SweptProfile, String> {
    die_shape("double_dome_die", half_length, die)
}

fn die_shape(tool: &str, half_length: f64, die: &DieShape) -> Result<SweptProfile, String> {
    let DieShape {
        opening_radius,
        fillet_radius,
        outer_radius,
        depth,
    } = *die;
    check_non_negative(tool, "half_length", half_length)?;
    check_positive(tool, "opening_radius", opening_radius)?;
    check_positive(tool, "fillet_radius", fillet_radius)?;
    check_positive(tool, "outer_radius", outer_radius)?;
    check_positive(tool, "depth", depth)?;
    if fillet_radius >= opening_radius {
        return Err(format!(
            "{tool}: fillet_radius ({fillet_radius}) must be smaller than opening_radius \
             ({opening_radius})"
        ));
    }
    if outer_radius <= opening_radius + fillet_radius {
        return Err(format!(
            "{tool}: outer_radius ({outer_radius}) must exceed opening_radius + fillet_radius \
             ({})",
            opening_radius + fillet_radius
        ));
    }
    if depth <= fillet_radius {
        return Err(format!(
            "{tool}: depth ({depth}) must exceed fillet_radius ({fillet_radius}) so the hole has a \
             wall above the fillet"
        ));
    }
    Ok(SweptProfile::new(
        die_profile(opening_radius, fillet_radius, outer_radius, depth),
        half_length,
    ))
}

/// Tool name in the matched die's messages.
const MATCHED_DIE: &str = "double_dome_matched_die";

/// The sizes of a matched die: see [`double_dome_matched_die`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchedDie {
    /// Radius `R` of the punch's crown (of [`double_dome_punch`]) the die is matched to.
    pub punch_radius: f64,
    /// Uniform gap `g` between punch and cavity at closure: the blank's thickness and clearance.
    pub gap: f64,
    /// Radius `Rf` of the fillet between the plate and the cavity.
    pub fillet_radius: f64,
    /// Distance of the plate's outer rim from the ridge (from the axis).
    pub outer_radius: f64,
    /// Travel `S` of the punch up the stroke axis, from its apex at `z = 0`, at closure.
    pub closed_travel: f64,
}

/// Matched (female) die of the double-dome punch (of the hemisphere punch for
/// `half_length = 0`): the cavity the punch of radius `R` fills with the uniform gap `g` once it
/// has travelled `S` up the stroke axis, so that the blank is formed between two tools rather
/// than drawn into an open hole. It is the punch's crown offset by `g`: at closure the crown's
/// centre line lies at `z = S - R`, so the cavity's cap is the offset at distance `R + g` from
/// that line, its top at `z = S + g`, and below the crown's equator a wall at distance `R + g`
/// from the ridge faces the punch's skirt.
///
/// Around the cavity, a flat plate in `z = 0` runs in from `outer_radius`, rounded into the
/// cavity by a fillet of radius `Rf` (a convex edge seen from the blank, centre line at
/// `z = Rf`) tangent to the plate:
///
/// - *deep* (`S - R > Rf`): the fillet turns through 90° into the wall, which rises from
///   `z = Rf` to the equator `z = S - R`, where the cap begins;
/// - *shallow* (`S - R <= Rf`): the equator is too low for a wall, and the fillet is tangent to
///   the cap itself, its centre line at distance `R + g + Rf` from the cap's.
///
/// Every joint is tangent (C1). Normals point down on the plate and into the cavity elsewhere,
/// towards the blank. The fillet lies outside the cap's offset, so at closure no point of the
/// punch is nearer to the die than `g`.
///
/// The cap turns through `90° - a`, `a` the angle of the fillet's tangency above the equator
/// (0 when deep); it has a top above the rim exactly when `S + g > 0`, which positive sizes
/// ensure, so a size is refused only when it is not positive and finite, when `S + g` is too
/// small against `R + Rf` for the cap to turn at all in floating point, or when
/// `outer_radius` does not reach beyond the fillet's start on the plate.
pub fn double_dome_matched_die(
    half_length: f64,
    die: &MatchedDie,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    let shape = double_dome_matched_die_shape(half_length, die)?;
    triangulated(MATCHED_DIE, &shape, resolution)
}

/// The exact surface of [`double_dome_matched_die`].
pub fn double_dome_matched_die_shape(
    half_length: f64,
    die: &MatchedDie,
) -> Result<SweptProfile, String> {
    check_non_negative(MATCHED_DIE, "half_length", half_length)?;
    let rim = checked_cavity_rim(die)?;
    Ok(SweptProfile::new(
        matched_die_profile(die, &rim),
        half_length,
    ))
}

/// Where the fillet of a matched die sits: what the cases of [`double_dome_matched_die`] change.
#[derive(Clone, Copy, Debug)]
struct CavityRim {
    /// Distance of the fillet's centre line from the ridge: where the fillet leaves the plate.
    fillet_r: f64,
    /// Angle (rad) of the fillet's tangency with the cap, above the cap centre's level: 0 when
    /// the fillet meets a wall.
    cap_from: f64,
}

/// The rim of `die`'s cavity, or the reason the sizes make none.
fn checked_cavity_rim(die: &MatchedDie) -> Result<CavityRim, String> {
    check_positive(MATCHED_DIE, "punch_radius", die.punch_radius)?;
    check_positive(MATCHED_DIE, "gap", die.gap)?;
    check_positive(MATCHED_DIE, "fillet_radius", die.fillet_radius)?;
    check_positive(MATCHED_DIE, "outer_radius", die.outer_radius)?;
    check_positive(MATCHED_DIE, "closed_travel", die.closed_travel)?;
    let rim = cavity_rim(die);
    if rim.cap_from >= FRAC_PI_2 {
        return Err(format!(
            "{MATCHED_DIE}: closed_travel + gap ({}) must be large enough against \
             punch_radius + fillet_radius ({}) for the cavity to rise above its rim",
            die.closed_travel + die.gap,
            die.punch_radius + die.fillet_radius
        ));
    }
    if die.outer_radius <= rim.fillet_r {
        return Err(format!(
            "{MATCHED_DIE}: outer_radius ({}) must exceed the distance at which the fillet \
             leaves the plate ({})",
            die.outer_radius, rim.fillet_r
        ));
    }
    Ok(rim)
}

/// The fillet's place. Deep, it meets the wall at the cap's level `a = 0`, its centre line at
/// `R + g + Rf`. Shallow, its centre line lies `drop = Rf - (S - R) >= 0` above the cap's and
/// `R + g + Rf` from it, hence at `sqrt((R + g + Rf)^2 - drop^2)` from the ridge; the
/// difference of squares is factored, `R + g + Rf - drop = S + g`, so that a small `S + g`
/// keeps its digits.
fn cavity_rim(die: &MatchedDie) -> CavityRim {
    let reach = die.punch_radius + die.gap + die.fillet_radius;
    let drop = die.fillet_radius - (die.closed_travel - die.punch_radius);
    if drop <= 0.0 {
        return CavityRim {
            fillet_r: reach,
            cap_from: 0.0,
        };
    }
    let fillet_r = ((die.closed_travel + die.gap) * (reach + drop)).sqrt();
    CavityRim {
        fillet_r,
        cap_from: drop.atan2(fillet_r),
    }
}

/// Matched die profile from the outer rim inward: the plate along `z = 0`, the fillet (angle
/// from -90° down to `a - 180°` about its centre), the wall up when deep, then the cap (angle
/// from `a` up to 90° about `(0, S - R)`), ending on the ridge at the cavity's top. Going inward
/// and up puts the left normal down on the plate and into the cavity (towards the cap's centre)
/// after it, as in [`die_profile`].
fn matched_die_profile(die: &MatchedDie, rim: &CavityRim) -> Vec<ProfilePiece> {
    let cavity = die.punch_radius + die.gap;
    let (fillet, equator) = (die.fillet_radius, die.closed_travel - die.punch_radius);
    let mut pieces = vec![
        ProfilePiece::Line {
            from: [die.outer_radius, 0.0],
            to: [rim.fillet_r, 0.0],
        },
        ProfilePiece::Arc {
            centre: [rim.fillet_r, fillet],
            radius: fillet,
            from: -FRAC_PI_2,
            to: rim.cap_from - PI,
        },
    ];
    if equator > fillet {
        pieces.push(ProfilePiece::Line {
            from: [cavity, fillet],
            to: [cavity, equator],
        });
    }
    pieces.push(ProfilePiece::Arc {
        centre: [0.0, equator],
        radius: cavity,
        from: rim.cap_from,
        to: FRAC_PI_2,
    });
    pieces
}

/// Blank holder: the flat annulus `inner_radius <= r <= outer_radius` in `z = 0`, below the
/// blank, with normal `+z`. Its inner radius must clear the punch (not checked here: the tools
/// are independent).
pub fn blank_holder(
    inner_radius: f64,
    outer_radius: f64,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    stadium_holder("blank_holder", 0.0, inner_radius, outer_radius, resolution)
}

/// Blank holder of the double-dome set-up: the flat ring in `z = 0` between the distances
/// `inner_radius` and `outer_radius` from the ridge segment `|x| <= half_length`, normal `+z`.
/// `half_length = 0` gives [`blank_holder`].
pub fn double_dome_holder(
    half_length: f64,
    inner_radius: f64,
    outer_radius: f64,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    stadium_holder(
        "double_dome_holder",
        half_length,
        inner_radius,
        outer_radius,
        resolution,
    )
}

fn stadium_holder(
    tool: &str,
    half_length: f64,
    inner_radius: f64,
    outer_radius: f64,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    let shape = holder_shape(tool, half_length, inner_radius, outer_radius)?;
    triangulated(tool, &shape, resolution)
}

/// The exact surface of [`double_dome_holder`] (of [`blank_holder`] for `half_length = 0`).
pub fn double_dome_holder_shape(
    half_length: f64,
    inner_radius: f64,
    outer_radius: f64,
) -> Result<SweptProfile, String> {
    holder_shape(
        "double_dome_holder",
        half_length,
        inner_radius,
        outer_radius,
    )
}

fn holder_shape(
    tool: &str,
    half_length: f64,
    inner_radius: f64,
    outer_radius: f64,
) -> Result<SweptProfile, String> {
    check_non_negative(tool, "half_length", half_length)?;
    check_positive(tool, "inner_radius", inner_radius)?;
    check_positive(tool, "outer_radius", outer_radius)?;
    if outer_radius <= inner_radius {
        return Err(format!(
            "{tool}: outer_radius ({outer_radius}) must exceed inner_radius ({inner_radius})"
        ));
    }
    // Profile outward: its left normal (-z', r') is then +z (see `sweep`).
    let plate = ProfilePiece::Line {
        from: [inner_radius, 0.0],
        to: [outer_radius, 0.0],
    };
    Ok(SweptProfile::new(vec![plate], half_length))
}

/// Double-dome punch, a (choice) simplifying the woven-composites "double dome" benchmark to a
/// smooth shape of double curvature: the hemisphere punch stretched along `x`. Its crown is the
/// set of points at distance `radius` above the ridge segment `|x| <= half_length`, `y = 0`,
/// `z = -radius`: a half cylinder of radius `radius` along `x` in the middle, closed by two
/// quarter spheres at `x = ±half_length`; below the crown's "equator" (`z = -radius`) a vertical
/// skirt of height `skirt_height` follows the stadium-shaped outline.
///
/// The surface is the offset of a segment, hence C1: cylinder and spheres meet tangentially at
/// `x = ±half_length`. `half_length = 0` gives [`hemisphere_punch_with_skirt`]. Normals point
/// away from the ridge, towards the blank.
pub fn double_dome_punch(
    half_length: f64,
    radius: f64,
    skirt_height: f64,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    let shape = double_dome_punch_shape(half_length, radius, skirt_height)?;
    triangulated("double_dome_punch", &shape, resolution)
}

/// The exact surface of [`double_dome_punch`] (of [`hemisphere_punch_with_skirt`] for
/// `half_length = 0`).
pub fn double_dome_punch_shape(
    half_length: f64,
    radius: f64,
    skirt_height: f64,
) -> Result<SweptProfile, String> {
    punch_shape("double_dome_punch", half_length, radius, skirt_height)
}

fn punch_shape(
    tool: &str,
    half_length: f64,
    radius: f64,
    skirt_height: f64,
) -> Result<SweptProfile, String> {
    check_non_negative(tool, "half_length", half_length)?;
    check_positive(tool, "radius", radius)?;
    check_non_negative(tool, "skirt_height", skirt_height)?;
    Ok(SweptProfile::new(
        punch_profile(radius, skirt_height),
        half_length,
    ))
}

/// The triangles of `shape`, edges about `resolution` long (see the module's "Meshes").
fn triangulated(
    tool: &str,
    shape: &SweptProfile,
    resolution: f64,
) -> Result<TriangleSurface, String> {
    check_positive(tool, "resolution", resolution)?;
    let profile = sampled(shape.pieces(), resolution)?;
    sweep(tool, &profile, shape.half_length(), resolution)
}

/// Distance of the point `(x, y)` of the blank's plane from the ridge segment `|x| <=
/// half_length`, `y = 0` (from the axis for `half_length = 0`): the radius along which every
/// tool of a set is swept.
pub fn distance_from_ridge(half_length: f64, x: f64, y: f64) -> f64 {
    (x.abs() - half_length).max(0.0).hypot(y)
}

fn check_positive(tool: &str, name: &str, value: f64) -> Result<(), String> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "{tool}: {name} must be positive and finite, got {value}"
        ))
    }
}

fn check_non_negative(tool: &str, name: &str, value: f64) -> Result<(), String> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(format!(
            "{tool}: {name} must be zero or positive and finite, got {value}"
        ))
    }
}

/// Punch profile from the apex down: quarter circle `r = R cos a`, `z = -R + R sin a` for `a`
/// from 90° to 0°, then the skirt straight down. Going down and outward puts the profile's left
/// normal outward, towards the blank.
fn punch_profile(radius: f64, skirt_height: f64) -> Vec<ProfilePiece> {
    let mut pieces = vec![ProfilePiece::Arc {
        centre: [0.0, -radius],
        radius,
        from: FRAC_PI_2,
        to: 0.0,
    }];
    if skirt_height > 0.0 {
        pieces.push(ProfilePiece::Line {
            from: [radius, -radius],
            to: [radius, -radius - skirt_height],
        });
    }
    pieces
}

/// Die profile from the outer rim inward: the plate along `z = 0`, the fillet (angle `a` from
/// -90° to -180° about its centre, point `c + Rf (cos a, sin a)`), then the wall up. Going inward
/// puts the left normal down on the plate and towards the axis on the wall.
fn die_profile(opening: f64, fillet: f64, outer: f64, depth: f64) -> Vec<ProfilePiece> {
    let centre = [opening + fillet, fillet];
    vec![
        ProfilePiece::Line {
            from: [outer, 0.0],
            to: [centre[0], 0.0],
        },
        ProfilePiece::Arc {
            centre,
            radius: fillet,
            from: -FRAC_PI_2,
            to: -PI,
        },
        ProfilePiece::Line {
            from: [opening, fillet],
            to: [opening, depth],
        },
    ]
}

/// The points of a profile about `h` apart, each piece ending on its exact end point.
fn sampled(pieces: &[ProfilePiece], h: f64) -> Result<Vec<[f64; 2]>, String> {
    let [r0, z0] = pieces[0].start();
    let mut profile = Profile::start(r0, z0);
    for piece in pieces {
        let [r, z] = piece.finish();
        match *piece {
            ProfilePiece::Line { .. } => profile.line_to(r, z, h)?,
            ProfilePiece::Arc {
                centre,
                radius,
                from,
                to,
            } => profile.arc_to(centre, radius, from, to, [r, z], h)?,
        }
    }
    Ok(profile.points)
}

/// A polyline in the meridian half-plane `(r, z)`, `r >= 0`, sampled at about the target edge
/// length. Each sampled piece ends on its exact end point, so pieces join without gaps.
struct Profile {
    points: Vec<[f64; 2]>,
}

impl Profile {
    fn start(r: f64, z: f64) -> Self {
        Profile {
            points: vec![[r, z]],
        }
    }

    fn last(&self) -> [f64; 2] {
        self.points[self.points.len() - 1]
    }

    /// Straight line from the last point to `(r, z)` in equal steps of at most `h`.
    fn line_to(&mut self, r: f64, z: f64, h: f64) -> Result<(), String> {
        let [r0, z0] = self.last();
        let n = segments((r - r0).hypot(z - z0) / h)?;
        for k in 1..n {
            let f = k as f64 / n as f64;
            self.points.push([r0 + f * (r - r0), z0 + f * (z - z0)]);
        }
        self.points.push([r, z]);
        Ok(())
    }

    /// Circular arc about `centre` from angle `from` (the last point) to angle `to` (the point
    /// `end`, given exactly), in equal steps of at most `h` and at most [`MAX_ARC_STEP`].
    fn arc_to(
        &mut self,
        centre: [f64; 2],
        radius: f64,
        from: f64,
        to: f64,
        end: [f64; 2],
        h: f64,
    ) -> Result<(), String> {
        let sweep = (to - from).abs();
        let n = segments(radius * sweep / h)?.max(segments(sweep / MAX_ARC_STEP)?);
        for k in 1..n {
            let a = from + (to - from) * k as f64 / n as f64;
            self.points
                .push([centre[0] + radius * a.cos(), centre[1] + radius * a.sin()]);
        }
        self.points.push(end);
        Ok(())
    }
}

/// Number of segments `ceil(ratio)` (at least 1) of a piece `ratio` target lengths long, or an
/// error when the resolution is absurdly fine for the tool.
fn segments(ratio: f64) -> Result<usize, String> {
    if ratio > MAX_SEGMENTS {
        return Err(format!(
            "resolution is too fine: {ratio:.3e} segments on one piece (limit {MAX_SEGMENTS:e})"
        ));
    }
    Ok((ratio.ceil() as usize).max(1))
}

/// Segments of a half ring of radius `r` (r > 0).
fn half_ring_segments(r: f64, h: f64) -> Result<usize, String> {
    Ok(segments(PI * r / h)?.max(MIN_HALF_RING_SEGMENTS))
}

/// Segments of each straight side of a stadium ring of half-length `l` (0 when `l = 0`).
fn straight_segments(l: f64, h: f64) -> Result<usize, String> {
    if l == 0.0 {
        Ok(0)
    } else {
        segments(2.0 * l / h)
    }
}

/// A closed ring of vertices (indices may repeat where the ring collapses onto the axis), with a
/// parameter in `[0, RING_PERIOD)` that increases counter-clockwise seen from `+z` and means the
/// same position around the axis on every ring, so that rings can be stitched in order.
#[derive(Default)]
struct Ring {
    index: Vec<usize>,
    param: Vec<f64>,
}

impl Ring {
    fn push(&mut self, index: usize, param: f64) {
        self.index.push(index);
        self.param.push(param);
    }

    fn len(&self) -> usize {
        self.index.len()
    }

    /// Parameter of the entry after `i`, `RING_PERIOD` past the last one.
    fn next_param(&self, i: usize) -> f64 {
        if i + 1 < self.len() {
            self.param[i + 1]
        } else {
            RING_PERIOD
        }
    }
}

/// Sweeps `profile` around the stadium of half-length `half_length` centred on the origin along
/// `x` (a circle when `half_length = 0`) and stitches the rings.
///
/// Orientation: with profile tangent `(r', z')` and the ring parameter counter-clockwise, the
/// normal `dP/ds x dP/du` is proportional to `-z' n_h + r' e_z` (`n_h` the outward horizontal
/// normal of the ring): the left normal of the profile in the `(r, z)` plane. Profiles are
/// therefore written in the direction whose left side faces the blank.
fn sweep(
    tool: &str,
    profile: &[[f64; 2]],
    half_length: f64,
    h: f64,
) -> Result<TriangleSurface, String> {
    let r_max = profile.iter().map(|p| p[0]).fold(0.0, f64::max);
    let ring_size = 2 * (half_ring_segments(r_max, h)? + straight_segments(half_length, h)?);
    let estimate = profile.len() as f64 * ring_size as f64;
    if estimate > MAX_VERTICES {
        return Err(format!(
            "{tool}: resolution ({h}) is too fine: about {estimate:.2e} vertices \
             (limit {MAX_VERTICES:e})"
        ));
    }
    let mut vertices = Vec::new();
    let mut rings = Vec::with_capacity(profile.len());
    for &[r, z] in profile {
        rings.push(ring(r, z, half_length, h, &mut vertices)?);
    }
    let mut triangles = Vec::new();
    for pair in rings.windows(2) {
        stitch(&pair[0], &pair[1], &mut triangles);
    }
    Ok(TriangleSurface {
        vertices,
        triangles,
    })
}

/// The ring of profile point `(r, z)`: right half circle about `(+l, 0)` (parameter 0..1), top
/// straight `y = r` from `x = l` to `-l` (1..2), left half circle about `(-l, 0)` (2..3), bottom
/// straight `y = -r` back (3..4). Each piece holds its start point but not its end point.
fn ring(r: f64, z: f64, l: f64, h: f64, vertices: &mut Vec<Vector3<f64>>) -> Result<Ring, String> {
    if r == 0.0 {
        return ridge(z, l, h, vertices);
    }
    let n_arc = half_ring_segments(r, h)?;
    let n_straight = straight_segments(l, h)?;
    let mut ring = Ring::default();
    let mut add = |x: f64, y: f64, param: f64| {
        vertices.push(Vector3::new(x, y, z));
        ring.push(vertices.len() - 1, param);
    };
    for k in 0..n_arc {
        let f = k as f64 / n_arc as f64;
        let a = -FRAC_PI_2 + PI * f;
        add(l + r * a.cos(), r * a.sin(), f);
    }
    for k in 0..n_straight {
        let f = k as f64 / n_straight as f64;
        add(l - 2.0 * l * f, r, 1.0 + f);
    }
    for k in 0..n_arc {
        let f = k as f64 / n_arc as f64;
        let a = FRAC_PI_2 + PI * f;
        add(-l + r * a.cos(), r * a.sin(), 2.0 + f);
    }
    for k in 0..n_straight {
        let f = k as f64 / n_straight as f64;
        add(-l + 2.0 * l * f, -r, 3.0 + f);
    }
    Ok(ring)
}

/// The ring at `r = 0`: the ridge segment `|x| <= l` (a single pole when `l = 0`), traversed
/// there and back so its parameters match those of the rings around it.
fn ridge(z: f64, l: f64, h: f64, vertices: &mut Vec<Vector3<f64>>) -> Result<Ring, String> {
    let n = straight_segments(l, h)?;
    let first = vertices.len();
    for k in 0..=n {
        let x = if n == 0 {
            0.0
        } else {
            l - 2.0 * l * k as f64 / n as f64
        };
        vertices.push(Vector3::new(x, 0.0, z));
    }
    let mut ring = Ring::default();
    ring.push(first, 0.0);
    for k in 0..n {
        ring.push(first + k, 1.0 + k as f64 / n as f64);
    }
    ring.push(first + n, 2.0);
    for k in 0..n {
        ring.push(first + n - k, 3.0 + k as f64 / n as f64);
    }
    Ok(ring)
}

/// Triangles between ring `a` and the next ring `b` along the profile: walk both rings in
/// parameter order, always advancing the ring whose next vertex comes first, so every triangle
/// spans one edge of one ring and a vertex of the other. Triangles `(a_j, b_k, a_j+1)` and
/// `(a_j, b_k, b_k+1)` have normal along `dP/ds x dP/du` (see [`sweep`]). Triangles with a
/// repeated vertex (where a ring collapses onto the axis) are skipped.
fn stitch(a: &Ring, b: &Ring, triangles: &mut Vec<[usize; 3]>) {
    let (na, nb) = (a.len(), b.len());
    let (mut j, mut k) = (0, 0);
    while j < na || k < nb {
        let advance_a = k == nb || (j < na && a.next_param(j) <= b.next_param(k));
        let triangle = if advance_a {
            let t = [a.index[j], b.index[k % nb], a.index[(j + 1) % na]];
            j += 1;
            t
        } else {
            let t = [a.index[j % na], b.index[k], b.index[(k + 1) % nb]];
            k += 1;
            t
        };
        let [p, q, s] = triangle;
        if p != q && q != s && s != p {
            triangles.push(triangle);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(s: &TriangleSurface) -> f64 {
        s.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| s.vertices[i]);
                0.5 * (b - a).cross(&(c - a)).norm()
            })
            .sum()
    }

    #[test]
    fn blank_holder_area_is_that_of_the_annulus() {
        let s = blank_holder(60.0, 100.0, 1.0).unwrap();
        let exact = PI * (100.0f64.powi(2) - 60.0f64.powi(2));
        assert!((area(&s) - exact).abs() / exact < 1e-3);
    }

    #[test]
    fn every_vertex_of_a_tool_is_used() {
        let s = double_dome_punch(30.0, 20.0, 10.0, 3.0).unwrap();
        let mut used = vec![false; s.vertices.len()];
        for t in &s.triangles {
            for &i in t {
                used[i] = true;
            }
        }
        assert!(used.iter().all(|&u| u));
    }

    #[test]
    fn absurd_resolution_is_an_error_not_an_allocation() {
        let e = hemisphere_punch(50.0, 1e-300).unwrap_err();
        assert!(e.contains("resolution"), "{e}");
    }

    /// Punch radius, gap and fillet radius of the matched dies below.
    const R: f64 = 50.0;
    const GAP: f64 = 1.5;
    const FILLET: f64 = 8.0;
    /// Travels at closure: deep (`S - R = 25 > Rf`, a wall from `z = 8` to 25) and shallow
    /// (`S < R`: the fillet meets the cap, whose centre is below the plate).
    const DEEP: f64 = 75.0;
    const SHALLOW: f64 = 30.0;

    fn matched(closed_travel: f64) -> MatchedDie {
        MatchedDie {
            punch_radius: R,
            gap: GAP,
            fillet_radius: FILLET,
            outer_radius: 120.0,
            closed_travel,
        }
    }

    /// The point of a surface swept around the ridge of `l` at profile point `(r, z)` and ring
    /// parameter `u` (see `ring`).
    fn swept_point(l: f64, [r, z]: [f64; 2], u: f64) -> Vector3<f64> {
        let f = u.fract();
        let (x, y) = match u as usize {
            0 => (
                l + r * (PI * f - FRAC_PI_2).cos(),
                r * (PI * f - FRAC_PI_2).sin(),
            ),
            1 => (l - 2.0 * l * f, r),
            2 => (
                -l + r * (PI * f + FRAC_PI_2).cos(),
                r * (PI * f + FRAC_PI_2).sin(),
            ),
            _ => (-l + 2.0 * l * f, -r),
        };
        Vector3::new(x, y, z)
    }

    /// At closure every point of the punch's exact surface (crown and skirt, moved up by `S`)
    /// lies at least `g` in front of the die, and exactly `g` wherever it faces the cap or the
    /// wall, which includes everything above the fillet's centre line `z = Rf`.
    #[test]
    fn at_closure_the_gap_to_the_punch_is_uniform() {
        for half_length in [0.0, 30.0] {
            for travel in [DEEP, SHALLOW] {
                let die = double_dome_matched_die_shape(half_length, &matched(travel)).unwrap();
                let punch = double_dome_punch_shape(half_length, R, 40.0).unwrap();
                let mut facing = 0;
                for piece in punch.pieces() {
                    for i in 0..=60 {
                        let [r, z] = piece.point_at(i as f64 / 60.0);
                        for u in [0.0, 0.35, 1.5, 2.8, 3.6] {
                            let p = swept_point(half_length, [r, z + travel], u);
                            let d = die.nearest(&p).distance;
                            let case = format!("l = {half_length}, S = {travel}, {p}");
                            assert!(d > GAP - 1e-9, "{case}: {d}");
                            if z + travel >= FILLET {
                                assert!((d - GAP).abs() < 1e-9, "{case}: {d}");
                                facing += 1;
                            }
                        }
                    }
                }
                assert!(facing >= 100, "{facing}");
            }
        }
    }

    /// Unit tangent of a piece at its start or finish, in its direction.
    fn tangent(piece: &ProfilePiece, at_finish: bool) -> [f64; 2] {
        match *piece {
            ProfilePiece::Line { from, to } => {
                let length = (to[0] - from[0]).hypot(to[1] - from[1]);
                [(to[0] - from[0]) / length, (to[1] - from[1]) / length]
            }
            ProfilePiece::Arc { from, to, .. } => {
                let a = if at_finish { to } else { from };
                let s = (to - from).signum();
                [-s * a.sin(), s * a.cos()]
            }
        }
    }

    /// Consecutive pieces share their end points and tangents, deep, at the switch between
    /// the cases (`S = R + Rf`), shallow, and very shallow (cap centre far below the plate);
    /// the profile runs from the plate's rim to the cavity's top on the axis.
    #[test]
    fn the_matched_die_profile_is_tangent_continuous() {
        for (travel, pieces) in [(DEEP, 4), (R + FILLET, 3), (SHALLOW, 3), (2.0, 3)] {
            let shape = double_dome_matched_die_shape(0.0, &matched(travel)).unwrap();
            let p = shape.pieces();
            assert_eq!(p.len(), pieces, "S = {travel}");
            assert_eq!(p[0].start(), [120.0, 0.0]);
            assert_eq!(p[p.len() - 1].finish(), [0.0, travel + GAP]);
            for pair in p.windows(2) {
                let (a, b) = (pair[0].finish(), pair[1].start());
                assert!(
                    (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-12,
                    "S = {travel}: {a:?} {b:?}"
                );
                let (ta, tb) = (tangent(&pair[0], true), tangent(&pair[1], false));
                assert!((ta[0] - tb[0]).hypot(ta[1] - tb[1]) < 1e-12, "S = {travel}");
            }
        }
    }

    /// The exact normal is `-z` at the cavity's top and on the plate, and every triangle of
    /// the mesh faces the same way as the exact surface at its centroid.
    #[test]
    fn matched_die_normals_point_down_and_into_the_cavity() {
        for half_length in [0.0, 30.0] {
            for travel in [DEEP, SHALLOW] {
                let sizes = matched(travel);
                let shape = double_dome_matched_die_shape(half_length, &sizes).unwrap();
                let below_top = Vector3::new(0.5 * half_length, 0.0, travel + GAP - 1.0);
                let top = shape.nearest(&below_top);
                assert!((top.normal + Vector3::z()).norm() < 1e-12, "{}", top.normal);
                assert!((top.distance - 1.0).abs() < 1e-12);
                let plate = shape.nearest(&Vector3::new(half_length, 110.0, -0.5));
                assert!(
                    (plate.normal + Vector3::z()).norm() < 1e-12,
                    "{}",
                    plate.normal
                );
                assert!((plate.distance - 0.5).abs() < 1e-12);
                let mesh = double_dome_matched_die(half_length, &sizes, 2.0).unwrap();
                for (k, t) in mesh.triangles.iter().enumerate() {
                    let [a, b, c] = t.map(|i| mesh.vertices[i]);
                    let exact = shape.nearest(&((a + b + c) / 3.0)).normal;
                    assert!(mesh.normal(k).dot(&exact) > 0.9, "triangle {k}");
                }
            }
        }
    }

    /// Sizes that make no cavity are refused, naming what is wrong; the least outer radius
    /// beyond the fillet is accepted.
    #[test]
    fn matched_die_sizes_without_a_cavity_are_refused() {
        let deep = matched(DEEP);
        let cases = [
            (
                MatchedDie {
                    punch_radius: 0.0,
                    ..deep
                },
                "punch_radius must be positive",
            ),
            (MatchedDie { gap: -1.0, ..deep }, "gap must be positive"),
            (
                MatchedDie {
                    fillet_radius: f64::NAN,
                    ..deep
                },
                "fillet_radius must be positive",
            ),
            (
                MatchedDie {
                    outer_radius: 0.0,
                    ..deep
                },
                "outer_radius must be positive",
            ),
            (
                MatchedDie {
                    closed_travel: 0.0,
                    ..deep
                },
                "closed_travel must be positive",
            ),
            (
                MatchedDie {
                    closed_travel: f64::INFINITY,
                    ..deep
                },
                "closed_travel must be positive",
            ),
            (
                MatchedDie {
                    outer_radius: 59.5,
                    ..deep
                },
                "outer_radius (59.5) must exceed",
            ),
            (
                MatchedDie {
                    outer_radius: 52.0,
                    ..matched(SHALLOW)
                },
                "outer_radius (52) must exceed",
            ),
            (
                MatchedDie {
                    closed_travel: 1e-300,
                    gap: 1e-300,
                    ..deep
                },
                "cavity to rise above",
            ),
        ];
        for (sizes, message) in cases {
            let e = double_dome_matched_die_shape(0.0, &sizes).unwrap_err();
            assert!(e.starts_with("double_dome_matched_die: "), "{e}");
            assert!(e.contains(message), "{e}");
        }
        let e = double_dome_matched_die_shape(-1.0, &deep).unwrap_err();
        assert!(e.contains("half_length must be zero or positive"), "{e}");
        let e = double_dome_matched_die(0.0, &deep, 0.0).unwrap_err();
        assert!(e.contains("resolution must be positive"), "{e}");
        let fits = MatchedDie {
            outer_radius: 59.5 + 1e-9,
            ..deep
        };
        assert!(double_dome_matched_die_shape(0.0, &fits).is_ok());
    }
}
