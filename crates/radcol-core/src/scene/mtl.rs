//! MTL input: the materials of an OBJ's `mtllib` statements, `Kd` as ρ
//! and `Ke` as E, every statement with its line.

use super::scan::{rest, syntax};
use super::validate::check_material;
use super::{Material, SceneError};

/// Parses an MTL text: every material needs `Kd` (three numbers in [0, 1));
/// `Ke` (three numbers ≥ 0) defaults to 0; other statements are tallied
/// into one warning per kind.
pub(super) fn parse_mtl(
    file: &str,
    text: &str,
    warnings: &mut Vec<String>,
) -> Result<Vec<Material>, SceneError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    struct Pending {
        name: String,
        line: usize,
        kd: Option<([f64; 3], usize)>,
        ke: Option<([f64; 3], usize)>,
    }
    let at = |line: usize| format!("{file}:{line}");
    let close = |p: Pending| -> Result<Material, SceneError> {
        let Some((rho, kd_line)) = p.kd else {
            return Err(SceneError::MissingKd {
                at: at(p.line),
                material: p.name,
            });
        };
        let (emission, ke_line) = p.ke.unwrap_or(([0.0; 3], p.line));
        let m = Material {
            name: p.name,
            rho,
            emission,
        };
        check_material(
            &Material {
                emission: [0.0; 3],
                ..m.clone()
            },
            &at(kd_line),
        )?;
        check_material(
            &Material {
                rho: [0.0; 3],
                ..m.clone()
            },
            &at(ke_line),
        )?;
        Ok(m)
    };
    let mut out = Vec::new();
    let mut current: Option<Pending> = None;
    let mut ignored = super::ignored::Ignored::default();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        let three = |words: std::str::SplitWhitespace| -> Result<[f64; 3], SceneError> {
            let nums: Vec<f64> = words
                .map(|w| w.parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| syntax(at(line_no), format!("cannot parse '{line}'")))?;
            <[f64; 3]>::try_from(nums).map_err(|_| {
                syntax(
                    at(line_no),
                    format!("'{line}': {keyword} needs exactly three numbers (r g b)"),
                )
            })
        };
        match keyword {
            "newmtl" => {
                if let Some(p) = current.take() {
                    out.push(close(p)?);
                }
                let name = rest(line, keyword);
                if name.is_empty() {
                    return Err(syntax(at(line_no), "newmtl without a name"));
                }
                current = Some(Pending {
                    name: name.into(),
                    line: line_no,
                    kd: None,
                    ke: None,
                });
            }
            "Kd" | "Ke" | "Ka" | "Ks" => {
                let v = three(words)?;
                let Some(p) = current.as_mut() else {
                    return Err(syntax(at(line_no), format!("{keyword} before any newmtl")));
                };
                match keyword {
                    "Kd" => p.kd = Some((v, line_no)),
                    "Ke" => p.ke = Some((v, line_no)),
                    k => ignored.note(k, line_no),
                }
            }
            "" => {}
            k if k.starts_with('#') => {}
            k => ignored.note(k, line_no),
        }
    }
    warnings.extend(ignored.warnings(file));
    if let Some(p) = current.take() {
        out.push(close(p)?);
    }
    Ok(out)
}
