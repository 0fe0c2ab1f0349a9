//! The objects of the glTF outputs: one node per scene object.

use crate::setup::Look;
use radcol_core::export::gltf::Layout;
use radcol_core::run::Mesh;

/// The glTF nodes of `mesh` as `look` asks: one per object, or one.
pub fn layout(mesh: &Mesh, look: &Look) -> Layout {
    Layout::of_mesh(mesh, &look.scene, look.metres_per_unit, look.objects)
}
