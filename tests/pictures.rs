//! The pictures of a forming run (docs/forming.md, "Pictures"): each is written, of its size,
//! not blank; its title and scale carry the run's values; the marked maximum is drawn in the
//! scale's colour for that value.

mod common;

use common::{repo_path, run_ok, scratch_dir};
use std::path::Path;
use thermostamp::forming::pictures::{
    write_pictures, Picture, FORCE_PLOT, MAP_SIZE, PLOT_SIZE, SHEAR_BLANK, SHEAR_MAP,
    THICKNESS_MAP, WRINKLE_MAP,
};
use thermostamp::forming::{FormingModel, Scenario};

/// The hemisphere example drawn 12 mm deep: a second or two.
const SHORT: [&str; 3] = [
    "process.stroke=12",
    "output.frames=0",
    "output.history_points=12",
];

/// Decoded RGB pixels and the size of the PNG at `path`.
fn decode(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut bytes = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut bytes).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    bytes.truncate(info.buffer_size());
    let pixels = bytes.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    (info.width, info.height, pixels)
}

/// A picture is not blank: a tenth of it or more is drawn, in many colours.
fn assert_drawn(path: &Path, pixels: &[[u8; 3]]) {
    let drawn = pixels.iter().filter(|p| **p != [255, 255, 255]).count();
    assert!(
        drawn > pixels.len() / 10,
        "{}: {drawn} of {} pixels drawn",
        path.display(),
        pixels.len()
    );
    let colours: std::collections::HashSet<_> = pixels.iter().collect();
    assert!(
        colours.len() > 50,
        "{}: {} colours",
        path.display(),
        colours.len()
    );
}

fn close(a: [u8; 3], b: [u8; 3], tolerance: u8) -> bool {
    a.iter().zip(b).all(|(x, y)| x.abs_diff(y) <= tolerance)
}

/// The hemisphere example, run short and its pictures written into a scratch folder.
fn short_hemisphere(name: &str) -> (Scenario, FormingModel, f64, Vec<Picture>) {
    let overrides: Vec<String> = SHORT.iter().map(|s| s.to_string()).collect();
    let scenario = Scenario::load(&repo_path("examples/hemisphere.toml"), &overrides).unwrap();
    let forming = FormingModel::new(&scenario).unwrap();
    let result = thermostamp::forming::run::run(&forming, None, None);
    assert!(result.outcome.is_ok(), "the short run finishes");
    let largest = result.records.last().unwrap().max_shear;
    let dir = scratch_dir("pictures", name);
    let pictures = write_pictures(&dir, &scenario, &forming, &result).unwrap();
    (scenario, forming, largest, pictures)
}

fn named<'a>(pictures: &'a [Picture], name: &str) -> &'a Picture {
    pictures
        .iter()
        .find(|p| p.path.file_name().is_some_and(|f| f == name))
        .unwrap_or_else(|| panic!("{name} not written"))
}

/// Every picture exists, has its size and is drawn; every title names the card, the
/// temperature, the holder force, the stroke and the solver.
#[test]
fn each_picture_is_written_drawn_and_titled_with_the_run() {
    let (_, _, _, pictures) = short_hemisphere("each");
    let names: Vec<String> = pictures
        .iter()
        .map(|p| p.path.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for expected in [
        FORCE_PLOT,
        SHEAR_MAP,
        SHEAR_BLANK,
        THICKNESS_MAP,
        WRINKLE_MAP,
    ] {
        assert!(
            names.iter().any(|n| n == expected),
            "{expected} in {names:?}"
        );
    }
    for picture in &pictures {
        let (width, height, pixels) = decode(&picture.path);
        let size = if picture.map.is_some() {
            MAP_SIZE
        } else {
            PLOT_SIZE
        };
        assert_eq!((width, height), size, "{}", picture.path.display());
        assert_drawn(&picture.path, &pixels);
        if let Some((map, _)) = &picture.map {
            for part in [
                "T300-3K 5HS / PPS prepreg",
                "300 °C",
                "holder 200 N",
                "stroke 12.0 mm",
                "implicit",
            ] {
                assert!(map.title.contains(part), "'{part}' not in '{}'", map.title);
            }
            assert!(map.marker.is_some(), "{}: extreme marked", map.title);
        }
    }
}

/// The shear maps' scale runs from 0 to the locking angle (above the largest shear here),
/// locking is marked on it, the largest shear is marked with the value the history records,
/// and the pixels at the mark have the scale's colour for it (dimmed by the light in the iso
/// view).
#[test]
fn the_shear_maps_mark_locking_and_the_largest_shear_in_its_colour() {
    let (_, _, largest, pictures) = short_hemisphere("shear");
    assert!(largest < 45.0, "{largest}");
    for name in [SHEAR_MAP, SHEAR_BLANK] {
        let picture = named(&pictures, name);
        let (map, frame) = picture.map.as_ref().unwrap();
        assert_eq!(map.colour_range(), (0.0, 45.0), "{name}");
        let limit = map.limit.as_ref().unwrap();
        assert_eq!((limit.value, limit.label.as_str()), (45.0, "locking 45°"));
        let marker = map.marker.as_ref().unwrap();
        assert_eq!(marker.label, format!("max {largest:.1}°"), "{name}");
        let cell = (0..map.values.len())
            .max_by(|&a, &b| map.values[a].total_cmp(&map.values[b]))
            .unwrap();
        let plotters::style::RGBColor(r, g, b) = map.colour_of(map.values[cell]);
        let shade = map.shade.get(cell).copied().unwrap_or(1.0);
        let dim = |c: u8| (f64::from(c) * shade).round() as u8;
        let expected = [dim(r), dim(g), dim(b)];
        let (width, _, pixels) = decode(&picture.path);
        let (column, row) = frame.pixel(marker.at);
        // a 7 x 7 block around the mark: the ring lies outside it, a tool's line may cross it
        let block: Vec<[u8; 3]> = (row - 3..=row + 3)
            .flat_map(|y| (column - 3..=column + 3).map(move |x| (x, y)))
            .map(|(x, y)| pixels[(y * width + x) as usize])
            .collect();
        let matching = block.iter().filter(|&&p| close(p, expected, 8)).count();
        assert!(
            matching >= block.len() / 3,
            "{name}: {matching} of {} pixels at ({column}, {row}) near {expected:?}: {block:?}",
            block.len()
        );
    }
}

/// The thickness map spans the values (thinning and thickening); the wrinkle map marks where
/// the flange counts as lifted (half the ply) and leaves the cells off the flange grey.
#[test]
fn the_thickness_and_wrinkle_maps_carry_their_scales() {
    let (_, forming, _, pictures) = short_hemisphere("thickness");
    let (thickness, _) = named(&pictures, THICKNESS_MAP).map.as_ref().unwrap();
    let finite = thickness.values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v), h.max(v)));
    assert_eq!(thickness.colour_range(), (lo, hi));
    assert!(thickness.value_label.contains("thickness change (%)"));
    let (wrinkles, _) = named(&pictures, WRINKLE_MAP).map.as_ref().unwrap();
    let half = 0.5 * forming.model.plies[0].laminate.reference_thickness();
    assert_eq!(wrinkles.limit.as_ref().map(|l| l.value), Some(half));
    assert!(
        wrinkles.values.iter().any(|v| v.is_nan()),
        "inside the die: no flange"
    );
    assert!(wrinkles.values.iter().any(|v| v.is_finite()), "the flange");
}

/// The command writes the pictures beside its other files and lists them.
#[test]
fn a_run_writes_and_lists_its_pictures() {
    let dir = scratch_dir("pictures", "cli");
    let folder = dir.join("out");
    let mut args = vec![
        "run",
        "examples/hemisphere.toml",
        "--output",
        folder.to_str().unwrap(),
    ];
    for set in SHORT {
        args.extend(["--set", set]);
    }
    let stdout = run_ok(&args);
    for name in [
        FORCE_PLOT,
        SHEAR_MAP,
        SHEAR_BLANK,
        THICKNESS_MAP,
        WRINKLE_MAP,
    ] {
        let path = folder.join(name);
        assert!(
            stdout.contains(&path.display().to_string()),
            "{name} listed"
        );
        let (_, _, pixels) = decode(&path);
        assert_drawn(&path, &pixels);
    }
}
