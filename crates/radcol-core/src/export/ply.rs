//! Binary little-endian PLY meshes with tone-mapped colours and raw radiosity.
//!
//! Vertices are written as the [`VertexMesh`] holds them: adjacent elements do
//! not share vertices, so the per-element discontinuities of u_n survive.

use super::{Context, Result};
use crate::render::{ToneMap, VertexMesh};
use std::io::Write;

/// The radiosity property names for `channel_names`: `radiosity` for one
/// (grey) channel, `radiosity_<name>` for each of three.
fn radiosity_properties(channel_names: &[&str]) -> Result<Vec<String>> {
    match channel_names {
        [_] => Ok(vec!["radiosity".into()]),
        [_, _, _] => channel_names
            .iter()
            .map(|n| {
                if n.is_empty() || !n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                    bail!("PLY: channel name '{n}' must be non-empty ASCII letters, digits or '_'");
                }
                Ok(format!("radiosity_{n}"))
            })
            .collect(),
        _ => bail!(
            "PLY: {} channel names given; expected 1 (grey) or 3 (R, G, B)",
            channel_names.len()
        ),
    }
}

/// Writes `mesh` as binary little-endian PLY: per vertex `x y z nx ny nz`
/// (float), `red green blue` (uchar, `tm` applied to the radiance u/π as for
/// images, sRGB-encoded), one float per channel with the raw radiosity u_n
/// and, when given, `error_estimate` (float: the estimated max error of the
/// vertex's element, relative as the caller says: `radcol solve` gives it
/// relative to the reflected light; one value per vertex); faces as
/// `list uchar int vertex_indices`.
pub fn write<W: Write>(
    mut w: W,
    mesh: &VertexMesh,
    channel_names: &[&str],
    tm: &ToneMap,
    error_estimate: Option<&[f32]>,
) -> Result<()> {
    let props = radiosity_properties(channel_names)?;
    let nv = mesh.positions.len();
    super::check_vertex_mesh("PLY", mesh, i32::MAX as u32)?;
    let colors = mesh.srgb8_colors(tm);
    let mut header = String::from("ply\nformat binary_little_endian 1.0\ncomment radcol: radiosity u_n per vertex; colours tone-mapped radiance u/pi\n");
    header += &format!("element vertex {nv}\n");
    for p in ["x", "y", "z", "nx", "ny", "nz"] {
        header += &format!("property float {p}\n");
    }
    for p in ["red", "green", "blue"] {
        header += &format!("property uchar {p}\n");
    }
    for p in &props {
        header += &format!("property float {p}\n");
    }
    if let Some(e) = error_estimate {
        if e.len() != nv {
            bail!("PLY: {} error values for {nv} vertices", e.len());
        }
        header += "property float error_estimate\n";
    }
    header += &format!(
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.indices.len() / 3
    );
    let mut buf = Vec::with_capacity(
        header.len() + nv * (27 + 4 * props.len()) + mesh.indices.len() / 3 * 13,
    );
    buf.extend_from_slice(header.as_bytes());
    for i in 0..nv {
        for x in mesh.positions[i].iter().chain(&mesh.normals[i]) {
            buf.extend_from_slice(&x.to_le_bytes());
        }
        buf.extend_from_slice(&colors[i]);
        for u in &mesh.values[i][..props.len()] {
            buf.extend_from_slice(&u.to_le_bytes());
        }
        if let Some(e) = error_estimate {
            buf.extend_from_slice(&e[i].to_le_bytes());
        }
    }
    for tri in mesh.indices.chunks_exact(3) {
        buf.push(3);
        for &v in tri {
            buf.extend_from_slice(&(v as i32).to_le_bytes());
        }
    }
    w.write_all(&buf).context("PLY: writing")?;
    w.flush().context("PLY: writing")?;
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::render::ToneOperator;
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Encoding, Property, PropertyType, ScalarType};

    /// Two elements of one triangle each, sharing an edge in space but not vertices.
    pub(crate) fn tiny() -> VertexMesh {
        VertexMesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, -0.5],
                [0.0, 1.0, 0.0],
            ],
            normals: vec![[0.0, 0.0, 1.0]; 6],
            values: vec![
                [0.0, 0.0, 0.0],
                [std::f32::consts::PI, 0.5, 2.0],
                [1.0, 1.0, 1.0],
                [2.0, 2.0, 2.0],
                [3.0, 0.25, 0.0],
                [1.5, 1.5, 1.5],
            ],
            indices: vec![0, 1, 2, 3, 4, 5],
            element: vec![0, 1],
        }
    }

    /// ply-rs-bw reads back the encoding, counts, property types and values.
    #[test]
    fn round_trip_rgb() {
        let mesh = tiny();
        // Linear, no auto: the colour of radiosity π is radiance 1 → 255.
        let tm = ToneMap {
            exposure: 0.0,
            operator: ToneOperator::Linear,
            auto: false,
        };
        let mut bytes = Vec::new();
        write(&mut bytes, &mesh, &["r", "g", "b"], &tm, None).unwrap();
        let ply = Parser::<DefaultElement>::new()
            .read_ply(&mut &bytes[..])
            .unwrap();
        assert_eq!(ply.header.encoding, Encoding::BinaryLittleEndian);
        assert_eq!(ply.header.elements["vertex"].count, 6);
        assert_eq!(ply.header.elements["face"].count, 2);
        let names: Vec<&str> = ply.header.elements["vertex"]
            .properties
            .keys()
            .map(|s| s.as_str())
            .collect();
        assert_eq!(
            names,
            [
                "x",
                "y",
                "z",
                "nx",
                "ny",
                "nz",
                "red",
                "green",
                "blue",
                "radiosity_r",
                "radiosity_g",
                "radiosity_b"
            ]
        );
        assert_eq!(
            ply.header.elements["face"].properties["vertex_indices"].data_type,
            PropertyType::List(ScalarType::UChar, ScalarType::Int)
        );
        let v = &ply.payload["vertex"][4];
        assert_eq!(v["x"], Property::Float(1.0));
        assert_eq!(v["z"], Property::Float(-0.5));
        assert_eq!(v["nz"], Property::Float(1.0));
        assert_eq!(v["radiosity_g"], Property::Float(0.25));
        let v = &ply.payload["vertex"][1];
        assert_eq!(v["red"], Property::UChar(255));
        // Blue: radiance 2/π = 0.63662 → sRGB 0.81905 → 208.86 → 209 (IEC 61966-2-1).
        let want =
            (255.0 * (1.055 * (2.0 / std::f64::consts::PI).powf(1.0 / 2.4) - 0.055)).round() as u8;
        assert_eq!(want, 209);
        assert_eq!(v["blue"], Property::UChar(want));
        assert_eq!(
            ply.payload["face"][1]["vertex_indices"],
            Property::ListInt(vec![3, 4, 5])
        );
    }

    /// The per-vertex error estimate is one more float, read back as written.
    #[test]
    fn error_estimate_property() {
        let mesh = tiny();
        let errors = [0.0f32, 1e-3, 2e-3, 3e-3, 4e-3, 5e-3];
        let mut bytes = Vec::new();
        write(
            &mut bytes,
            &mesh,
            &["u"],
            &ToneMap::default(),
            Some(&errors),
        )
        .unwrap();
        let ply = Parser::<DefaultElement>::new()
            .read_ply(&mut &bytes[..])
            .unwrap();
        assert_eq!(
            ply.header.elements["vertex"].properties["error_estimate"].data_type,
            PropertyType::Scalar(ScalarType::Float)
        );
        for (i, &e) in errors.iter().enumerate() {
            assert_eq!(
                ply.payload["vertex"][i]["error_estimate"],
                Property::Float(e)
            );
        }
    }

    #[test]
    fn grey_and_errors() {
        let mesh = tiny();
        let mut bytes = Vec::new();
        write(&mut bytes, &mesh, &["grey"], &ToneMap::default(), None).unwrap();
        let ply = Parser::<DefaultElement>::new()
            .read_ply(&mut &bytes[..])
            .unwrap();
        let props = &ply.header.elements["vertex"].properties;
        assert_eq!(props.len(), 10);
        assert!(props.contains_key("radiosity"));
        assert_eq!(ply.payload["vertex"][3]["radiosity"], Property::Float(2.0));
        assert!(write(Vec::new(), &mesh, &["r", "g"], &ToneMap::default(), None).is_err());
        assert!(write(
            Vec::new(),
            &mesh,
            &["r", "g b", "c"],
            &ToneMap::default(),
            None
        )
        .is_err());
        let short = [0.5f32; 5];
        assert!(write(Vec::new(), &mesh, &["u"], &ToneMap::default(), Some(&short)).is_err());
        let mut bad = tiny();
        bad.indices[4] = 6;
        let err = write(Vec::new(), &bad, &["u"], &ToneMap::default(), None).unwrap_err();
        assert!(
            err.to_string().contains("index 4 (triangle 1) = 6"),
            "{err}"
        );
    }
}
