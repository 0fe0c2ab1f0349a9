//! Changing a scene's materials by name: what relighting takes (new
//! emission or reflectance on the same surface, solved on the assembled
//! operator without reassembly).

use super::validate::check_material;
use super::{Scene, SceneError};

/// A new value for one side of a material, per colour channel (R, G, B).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialChange {
    /// Emitted radiosity E (MTL `Ke`): finite and ≥ 0.
    Emission([f64; 3]),
    /// Diffuse reflectance ρ (MTL `Kd`): in [0, 1).
    Reflectance([f64; 3]),
}

impl Scene {
    /// Applies `change` to every material named `name` (a scene may hold
    /// two of one name: its load warnings say so) and returns how many
    /// changed. The scene is left as it was when the name is unknown
    /// ([`SceneError::NoSuchMaterial`]) or a value is out of range
    /// ([`SceneError::Reflectance`], [`SceneError::Emission`]).
    pub fn change_material(
        &mut self,
        name: &str,
        change: MaterialChange,
    ) -> Result<usize, SceneError> {
        let at: Vec<usize> = (self.materials.iter().enumerate())
            .filter(|(_, m)| m.name == name)
            .map(|(i, _)| i)
            .collect();
        if at.is_empty() {
            let known: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
            return Err(SceneError::NoSuchMaterial {
                name: name.into(),
                known: known.join(", "),
            });
        }
        let mut changed = self.materials[at[0]].clone();
        match change {
            MaterialChange::Emission(e) => changed.emission = e,
            MaterialChange::Reflectance(r) => changed.rho = r,
        }
        check_material(&changed, "relighting")?;
        for &i in &at {
            let m = &mut self.materials[i];
            match change {
                MaterialChange::Emission(e) => m.emission = e,
                MaterialChange::Reflectance(r) => m.rho = r,
            }
        }
        Ok(at.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_builtin_by_an_unknown_name_lists_the_known_ones() {
        let err = Scene::builtin("cornel").unwrap_err().to_string();
        assert!(
            err.contains("'cornel'") && err.contains("cornell, "),
            "{err}"
        );
        assert_eq!(Scene::builtin("plates").unwrap().name, "plates");
    }

    #[test]
    fn a_change_reaches_every_material_of_its_name_or_none() {
        let mut scene = super::super::builtin("cornell")
            .expect("built in")
            .expect("loads");
        let light = scene.materials.iter().position(|m| m.is_emitter()).unwrap();
        let name = scene.materials[light].name.clone();
        let before = scene.materials.clone();
        let n = scene.change_material(&name, MaterialChange::Emission([1.0, 2.0, 3.0]));
        assert_eq!(n.unwrap(), 1);
        assert_eq!(scene.materials[light].emission, [1.0, 2.0, 3.0]);
        assert_eq!(scene.materials[light].rho, before[light].rho);
        let mut unchanged = scene.clone();
        let bad = unchanged.change_material(&name, MaterialChange::Reflectance([0.5, 1.0, 0.5]));
        assert!(
            matches!(bad, Err(SceneError::Reflectance { .. })),
            "{bad:?}"
        );
        let nan = unchanged.change_material(&name, MaterialChange::Emission([f64::NAN; 3]));
        assert!(matches!(nan, Err(SceneError::Emission { .. })), "{nan:?}");
        let missing = unchanged.change_material("nope", MaterialChange::Emission([0.0; 3]));
        let message = missing.unwrap_err().to_string();
        assert!(
            message.contains("'nope'") && message.contains(&name),
            "{message}"
        );
        assert_eq!(unchanged.materials, scene.materials);
    }
}
