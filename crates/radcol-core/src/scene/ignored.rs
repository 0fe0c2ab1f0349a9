//! OBJ and MTL statements radcol does not use, tallied per kind so that the
//! scene warns once per kind (count and first line) instead of dropping them
//! silently.

use std::collections::BTreeMap;

/// Per keyword: how many statements and the first one's 1-based line.
#[derive(Debug, Default)]
pub(super) struct Ignored(BTreeMap<String, (usize, usize)>);

impl Ignored {
    /// Records a statement `keyword` at `line`.
    pub fn note(&mut self, keyword: &str, line: usize) {
        self.0.entry(keyword.to_string()).or_insert((0, line)).0 += 1;
    }

    /// One warning per kind, naming `file`, the first line and why the
    /// statement does not matter (or what is used instead).
    pub fn warnings(&self, file: &str) -> Vec<String> {
        self.0
            .iter()
            .map(|(k, &(count, line))| {
                format!(
                    "{file}:{line}: {count} '{k}' statement{} ignored: {}",
                    if count == 1 { "" } else { "s" },
                    why(k)
                )
            })
            .collect()
    }
}

/// What an ignored keyword would have meant, and what radcol does instead.
fn why(keyword: &str) -> &'static str {
    match keyword {
        "vn" => "vertex normals (faces are flat; their lit side is the counter-clockwise one, whatever the normals say)",
        "s" => "smoothing groups (shading normals only; faces are flat)",
        "Ka" | "Ks" | "Ns" | "Ni" | "illum" | "Pr" | "Pm" | "Ps" | "Pc" | "Pcr" | "aniso" => {
            "not a diffuse property (radcol's surfaces are Lambertian: Kd and Ke only)"
        }
        "d" | "Tr" | "Tf" => "transparency (surfaces are opaque)",
        k if k.starts_with("map_") || k == "bump" || k == "disp" || k == "decal" || k == "refl" => {
            "a texture map (not sampled: Kd and Ke are used as given)"
        }
        _ => "not a statement radcol reads",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One warning per kind, with count, first line and reason.
    #[test]
    fn one_warning_per_kind() {
        let mut i = Ignored::default();
        i.note("vn", 4);
        i.note("vn", 9);
        i.note("map_Kd", 2);
        let w = i.warnings("a.obj");
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            w[0].starts_with("a.obj:2: 1 'map_Kd' statement ignored: a texture map"),
            "{w:?}"
        );
        assert!(
            w[1].starts_with("a.obj:4: 2 'vn' statements ignored: vertex normals"),
            "{w:?}"
        );
    }
}
