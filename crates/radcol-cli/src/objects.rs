//! The objects of the glTF outputs: one node per scene object.

use crate::export;
use crate::setup::Look;
use radcol_core::mesh::Mesh;

/// The glTF nodes: with a scene, one per object (the patch name's group, the
/// part before '/'), in the order they first appear; else one.
pub fn layout(mesh: &Mesh, look: &Look) -> export::gltf::Layout {
    let mut layout = export::gltf::Layout::single(&look.scene, mesh.len());
    layout.metres_per_unit = look.metres_per_unit;
    let patches = &mesh.surface().patches;
    if !look.objects {
        layout.object_of_patch = vec![0; patches.len()];
        return layout;
    }
    layout.objects.clear();
    let object_of_patch: Vec<u32> = patches
        .iter()
        .map(|p| {
            let group = p.name.split('/').next().unwrap_or(&p.name).to_string();
            match layout.objects.iter().position(|o| *o == group) {
                Some(i) => i as u32,
                None => {
                    layout.objects.push(group);
                    (layout.objects.len() - 1) as u32
                }
            }
        })
        .collect();
    layout.object_of_element = mesh
        .elements()
        .iter()
        .map(|e| object_of_patch[e.patch as usize])
        .collect();
    layout.object_of_patch = object_of_patch;
    layout
}
