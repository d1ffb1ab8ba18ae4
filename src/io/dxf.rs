//! A closed outline as an ASCII DXF drawing (AutoCAD R12, `AC1009`): the flat blank a cutting
//! table or a CAD program reads. The smallest complete R12 file: a header naming the version,
//! a layer table with the outline's layer, and one closed `POLYLINE` of `VERTEX` entities
//! (R12 has no `LWPOLYLINE`, which came with R14), in mm, z = 0.

use super::csv_table::number_text;
use std::path::Path;

/// The DXF text of the closed polygon `points` (mm, in order; the last joined to the first)
/// on `layer`.
pub fn dxf_text(points: &[[f64; 2]], layer: &str) -> String {
    let mut out = String::new();
    let mut pair = |code: i32, value: &str| {
        out.push_str(&format!("{code:>3}\n{value}\n"));
    };
    pair(0, "SECTION");
    pair(2, "HEADER");
    pair(9, "$ACADVER");
    pair(1, "AC1009");
    pair(0, "ENDSEC");
    pair(0, "SECTION");
    pair(2, "TABLES");
    pair(0, "TABLE");
    pair(2, "LAYER");
    pair(70, "1");
    pair(0, "LAYER");
    pair(2, layer);
    pair(70, "0");
    pair(62, "7"); // white/black: the default colour
    pair(6, "CONTINUOUS");
    pair(0, "ENDTAB");
    pair(0, "ENDSEC");
    pair(0, "SECTION");
    pair(2, "ENTITIES");
    pair(0, "POLYLINE");
    pair(8, layer);
    pair(66, "1"); // vertices follow
    pair(10, "0.0");
    pair(20, "0.0");
    pair(30, "0.0");
    pair(70, "1"); // closed
    for p in points {
        pair(0, "VERTEX");
        pair(8, layer);
        pair(10, &number_text(p[0]));
        pair(20, &number_text(p[1]));
        pair(30, "0.0");
    }
    pair(0, "SEQEND");
    pair(8, layer);
    pair(0, "ENDSEC");
    pair(0, "EOF");
    out
}

/// Writes [`dxf_text`] to `path` (a symbolic link there is refused, as for every result).
pub fn write_dxf(path: &Path, points: &[[f64; 2]], layer: &str) -> std::io::Result<()> {
    super::product_file::write(path, dxf_text(points, layer).as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The (code, value) pairs of a DXF text.
    fn pairs(text: &str) -> Vec<(i32, String)> {
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len() % 2, 0, "codes and values come in pairs");
        lines
            .chunks(2)
            .map(|c| (c[0].trim().parse().unwrap(), c[1].to_string()))
            .collect()
    }

    #[test]
    fn a_square_is_one_closed_polyline_on_its_layer() {
        let square = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.5]];
        let text = dxf_text(&square, "OUTLINE");
        let p = pairs(&text);
        let value = |code: i32, v: &str| (code, v.to_string());
        assert_eq!(
            p[..4],
            [
                value(0, "SECTION"),
                value(2, "HEADER"),
                value(9, "$ACADVER"),
                value(1, "AC1009")
            ]
        );
        assert_eq!(p.last(), Some(&value(0, "EOF")));
        assert!(
            p.contains(&value(2, "OUTLINE")),
            "the layer is in the table"
        );
        let polylines = p.iter().filter(|x| **x == value(0, "POLYLINE")).count();
        assert_eq!(polylines, 1);
        let start = p.iter().position(|x| *x == value(0, "POLYLINE")).unwrap();
        assert_eq!(p[start + 1], value(8, "OUTLINE"));
        assert!(p[start..].contains(&value(70, "1")), "closed");
        let vertices: Vec<(f64, f64)> = p
            .windows(5)
            .filter(|w| w[0] == value(0, "VERTEX"))
            .map(|w| (w[2].1.parse().unwrap(), w[3].1.parse().unwrap()))
            .collect();
        assert_eq!(
            vertices,
            [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.5)]
        );
        let sections = p.iter().filter(|x| **x == value(0, "SECTION")).count();
        let ends = p.iter().filter(|x| **x == value(0, "ENDSEC")).count();
        assert_eq!((sections, ends), (3, 3));
        assert_eq!(p.iter().filter(|x| **x == value(0, "SEQEND")).count(), 1);
    }
}
