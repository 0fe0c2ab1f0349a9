//! Shared checks and repairs of every scene input: triangles with their origin
//! (file:line or group/face) become a [`Scene`], or a [`SceneError`].

use super::raw::{duplicate_message, Capped, Dropped, RawScene, RawTriangle};
use super::{Material, Scene, SceneError, MAX_WARNINGS_PER_KIND};
use crate::geometry::{Identity, Patch, Surface};
use crate::visibility::is_convex_enclosure;
use glam::DVec3;
use std::collections::HashMap;
use std::sync::Arc;

/// The warning of a scene none of whose triangles emits.
pub(super) const NO_EMITTER: &str = "no triangle's material emits light (every Ke or emissive factor is zero): the solution is zero everywhere until an emission is given (relighting can give one)";

/// Bit pattern of a position, for exact hashing.
fn key(v: DVec3) -> [u64; 3] {
    v.to_array().map(|x| (x + 0.0).to_bits())
}

/// The triangle's cyclic order started at its smallest vertex: equal for the
/// same triangle in the same orientation.
pub(super) fn oriented_key(t: &[DVec3; 3]) -> [[u64; 3]; 3] {
    let k = t.map(key);
    let i = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
    [k[i], k[(i + 1) % 3], k[(i + 2) % 3]]
}

/// Checks materials (ρ in [0, 1), E finite and ≥ 0); `at(i)` names material `i`.
pub(crate) fn check_material(m: &Material, at: &str) -> Result<(), SceneError> {
    const C: [&str; 3] = ["R", "G", "B"];
    for c in 0..3 {
        if !(0.0..1.0).contains(&m.rho[c]) {
            return Err(SceneError::Reflectance {
                at: at.into(),
                material: m.name.clone(),
                component: C[c],
                value: m.rho[c],
            });
        }
        if !(m.emission[c].is_finite() && m.emission[c] >= 0.0) {
            return Err(SceneError::Emission {
                at: at.into(),
                material: m.name.clone(),
                component: C[c],
                value: m.emission[c],
            });
        }
    }
    Ok(())
}

/// Runs the shared repairs and warnings and builds the scene.
/// One warning per name that materials with different values share (two
/// `newmtl` of one name, or one name in two MTL files): each face keeps
/// the material it was given, and a change by name changes every one.
fn same_names(materials: &[Material]) -> Vec<String> {
    let mut out = Vec::new();
    for (i, m) in materials.iter().enumerate() {
        let first = materials.iter().position(|o| o.name == m.name) == Some(i);
        let others: Vec<&Material> = (materials[i + 1..].iter())
            .filter(|o| o.name == m.name && (o.rho != m.rho || o.emission != m.emission))
            .collect();
        if first && !others.is_empty() {
            let values: Vec<String> = std::iter::once(m)
                .chain(others)
                .map(|o| format!("ρ {:?}, E {:?}", o.rho, o.emission))
                .collect();
            out.push(format!(
                "{} materials are named '{}' with different values ({}): each face keeps the one it was given, and a change by that name changes all of them",
                values.len(),
                m.name,
                values.join("; ")
            ));
        }
    }
    out
}

pub(crate) fn finish(raw: RawScene) -> Result<Scene, SceneError> {
    let RawScene {
        name,
        materials,
        triangles,
        camera,
        mut warnings,
        source,
        duplicates,
    } = raw;
    if triangles.is_empty() {
        return Err(SceneError::Empty {
            name,
            detail: String::new(),
        });
    }
    warnings.extend(same_names(&materials));
    if let Some(c) = &camera {
        c.validate().map_err(|message| SceneError::Camera {
            name: name.clone(),
            message,
        })?;
    }
    let (lo, hi) = triangles.iter().flat_map(|t| t.vertices).fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(v), hi.max(v)),
    );
    let scale = (hi - lo).length();

    let (kept, degenerate) = drop_degenerate_and_duplicates(triangles, duplicates, &mut warnings);
    if kept.is_empty() {
        return Err(SceneError::Empty {
            name,
            detail: format!(" after dropping {degenerate} degenerate triangles"),
        });
    }

    let tris: Vec<[DVec3; 3]> = kept.iter().map(|t| t.vertices).collect();
    non_manifold_edges(&tris, &kept, &mut warnings);
    {
        let mut w = Capped::new(&mut warnings, "overlapping-triangles");
        for (i, j) in super::overlap::coplanar_overlaps(&tris, scale) {
            w.push(format!(
                "{}: overlaps the triangle at {} in the same plane, facing the same way: that area is counted twice",
                kept[j].at, kept[i].at
            ));
        }
    }
    {
        let mut w = Capped::new(&mut warnings, "too-thin");
        let mut said = std::collections::HashSet::new();
        for (i, j, gap) in super::overlap::facing_too_close(&tris, scale) {
            // Once per pair of input faces (a quad is two triangles).
            if !said.insert((kept[i].at.clone(), kept[j].at.clone())) {
                continue;
            }
            w.push(format!(
                "{}: faces the triangle at {} from {gap:.1e} away, below 1e-9 of the scene's size: \
                 the light between them cannot be resolved (a closed box this thin reads as a \
                 two-sided panel); make it thicker or one panel",
                kept[j].at, kept[i].at
            ));
        }
    }
    t_junctions(&tris, &kept, scale, &mut warnings);
    if !kept.iter().any(|t| materials[t.material].is_emitter()) {
        warnings.push(NO_EMITTER.to_string());
    }
    super::facing::facing_nothing(&tris, &kept, &materials, scale, &mut warnings);
    let (kept, imprinted) = super::imprint::contact_lines(kept, scale);

    let (patches, patch_material, patch_of) = patches_by_group(&kept, &materials);
    let uvs = texture_coordinates(&kept, &patch_of, patches.len(), &mut warnings);
    let mut origins = vec![Vec::new(); patches.len()];
    for (t, &j) in kept.iter().zip(&patch_of) {
        origins[j].push(t.origin.clone());
    }
    let surface = Surface {
        name: name.clone(),
        patches,
        convex_enclosure: is_convex_enclosure(&tris),
    };
    Ok(Scene {
        name,
        surface: Arc::new(surface),
        materials,
        patch_material,
        camera,
        warnings,
        source,
        imprinted,
        metres_per_unit: None,
        uvs,
        origins,
    })
}

/// The texture coordinates of every patch triangle, in the patches'
/// order, when every triangle has them; a warning when only some do.
fn texture_coordinates(
    kept: &[RawTriangle],
    patch_of: &[usize],
    patches: usize,
    warnings: &mut Vec<String>,
) -> Option<Vec<Vec<[[f64; 2]; 3]>>> {
    let with = kept.iter().filter(|t| t.uv.is_some()).count();
    if with < kept.len() {
        if with > 0 {
            let first = kept
                .iter()
                .find(|t| t.uv.is_none())
                .expect("some lack them");
            warnings.push(format!(
                "{}: {} of {} triangles have no texture coordinates (this one first): \
                 lightmaps generate their own charts instead of using the input's",
                first.at,
                kept.len() - with,
                kept.len()
            ));
        }
        return None;
    }
    let mut uvs: Vec<Vec<[[f64; 2]; 3]>> = vec![Vec::new(); patches];
    for (t, &j) in kept.iter().zip(patch_of) {
        uvs[j].push(t.uv.expect("all have them"));
    }
    Some(uvs)
}

/// Why a triangle is degenerate, judged by its own size: a sliver (area at
/// most 1e-12 of its longest edge squared, or not finite), or smaller than
/// the rounding of its coordinates (longest edge within 1e3 ulps of them).
/// A tolerance relative to the scene instead dropped a unit light when one
/// vertex of the scene lay at 1.2e8 (issue 12).
pub(super) fn degenerate_why([a, b, c]: [DVec3; 3]) -> Option<String> {
    let area = 0.5 * (b - a).cross(c - a).length();
    let longest = (b - a).length().max((c - b).length()).max((a - c).length());
    let reach = a.abs().max(b.abs()).max(c.abs()).max_element();
    if !area.is_finite() || area <= 1e-12 * longest * longest {
        Some(format!(
            "area {area:e} with longest edge {longest:e}: a sliver"
        ))
    } else if longest <= 1e3 * f64::EPSILON * reach {
        Some(format!(
            "longest edge {longest:e} is within rounding of its coordinates ({reach:e})"
        ))
    } else {
        None
    }
}

/// Drops degenerate triangles ([`degenerate_why`]) and duplicates (same
/// vertices, same orientation), with
/// a capped warning for each (after those the loader `dropped` already);
/// returns the kept triangles and how many were degenerate.
fn drop_degenerate_and_duplicates(
    triangles: Vec<RawTriangle>,
    dropped: Dropped,
    warnings: &mut Vec<String>,
) -> (Vec<RawTriangle>, usize) {
    let mut kept: Vec<RawTriangle> = Vec::with_capacity(triangles.len());
    let mut seen: HashMap<[[u64; 3]; 3], usize> = HashMap::new();
    let mut degenerate = 0;
    {
        let mut deg = Capped::new(warnings, "degenerate-triangle");
        // Listed after the degenerate ones; only as many as are listed are
        // formatted (33 M copies of one triangle held 33 M messages).
        let (mut dup_list, mut dup_more) = (dropped.listed, dropped.more);
        for t in triangles {
            if let Some(why) = degenerate_why(t.vertices) {
                deg.push(format!("{}: degenerate triangle ({why}) dropped", t.at));
                degenerate += 1;
                continue;
            }
            match seen.entry(oriented_key(&t.vertices)) {
                std::collections::hash_map::Entry::Occupied(_)
                    if dup_list.len() >= MAX_WARNINGS_PER_KIND =>
                {
                    dup_more += 1;
                }
                std::collections::hash_map::Entry::Occupied(e) => {
                    dup_list.push(duplicate_message(&t.at, &kept[*e.get()].at));
                }
                std::collections::hash_map::Entry::Vacant(e) => {
                    e.insert(kept.len());
                    kept.push(t);
                }
            }
        }
        drop(deg);
        let mut dup = Capped::new(warnings, "duplicate-triangle");
        for m in dup_list {
            dup.push(m);
        }
        dup.count_more(dup_more);
    }
    (kept, degenerate)
}

/// One patch per (group, material), in order of first appearance, with
/// each patch's material, and the patch of each triangle (whose triangles
/// keep their order).
fn patches_by_group(
    kept: &[RawTriangle],
    materials: &[Material],
) -> (Vec<Patch>, Vec<usize>, Vec<usize>) {
    let mut patch_of: HashMap<(String, usize), usize> = HashMap::new();
    let mut patches: Vec<Patch> = Vec::new();
    let mut patch_material = Vec::new();
    let mut of = Vec::with_capacity(kept.len());
    for t in kept {
        let j = *patch_of
            .entry((t.group.clone(), t.material))
            .or_insert_with(|| {
                patches.push(Patch {
                    name: format!("{}/{}", t.group, materials[t.material].name),
                    map: Arc::new(Identity),
                    triangles: Vec::new(),
                });
                patch_material.push(t.material);
                patches.len() - 1
            });
        patches[j].triangles.push(t.vertices);
        of.push(j);
    }
    (patches, patch_material, of)
}

/// Warns about edges shared by more than two triangles (hashing sorted
/// endpoints); a two-sided panel's coincident pair counts once.
fn non_manifold_edges(tris: &[[DVec3; 3]], raw: &[RawTriangle], warnings: &mut Vec<String>) {
    type Edge = (DVec3, DVec3, Vec<usize>);
    let mut edges: HashMap<([u64; 3], [u64; 3]), Edge> = HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        for e in 0..3 {
            let (p, q) = (t[e], t[(e + 1) % 3]);
            let (a, b) = (key(p), key(q));
            edges
                .entry(if a < b { (a, b) } else { (b, a) })
                .or_insert_with(|| (p, q, Vec::new()))
                .2
                .push(i);
        }
    }
    // The two sides of a two-sided panel are one sheet: count distinct
    // unoriented triangles per edge.
    let sheet = |i: usize| {
        let mut k = tris[i].map(key);
        k.sort();
        k
    };
    let sheets = |faces: &[usize]| {
        let mut k: Vec<_> = faces.iter().map(|&i| sheet(i)).collect();
        k.sort();
        k.dedup();
        k.len()
    };
    let mut bad: Vec<&Edge> = edges.values().filter(|e| sheets(&e.2) > 2).collect();
    bad.sort_by(|x, y| x.2.cmp(&y.2));
    let mut w = Capped::new(warnings, "non-manifold-edge");
    for (a, b, faces) in bad {
        let names: Vec<&str> = faces.iter().map(|&i| raw[i].at.as_str()).collect();
        w.push(format!(
            "non-manifold edge ({:.6}, {:.6}, {:.6})-({:.6}, {:.6}, {:.6}) shared by {} triangles: {}",
            a.x,
            a.y,
            a.z,
            b.x,
            b.y,
            b.z,
            faces.len(),
            names.join(", ")
        ));
    }
}

/// Warns about vertices lying inside another triangle's edge. Vertices go in a
/// uniform grid of cell size h (the mean edge length); each edge is walked in
/// steps of h and tests the vertices in the 27 cells around each step, so the
/// cost is O(n) for meshes of comparable edge lengths.
fn t_junctions(tris: &[[DVec3; 3]], raw: &[RawTriangle], scale: f64, warnings: &mut Vec<String>) {
    let mut first_face: HashMap<[u64; 3], usize> = HashMap::new();
    let mut verts: Vec<DVec3> = Vec::new();
    let mut vert_face: Vec<usize> = Vec::new();
    type Edge = (DVec3, DVec3, usize);
    let mut edges: HashMap<([u64; 3], [u64; 3]), Edge> = HashMap::new();
    let mut total_len = 0.0;
    for (i, t) in tris.iter().enumerate() {
        for e in 0..3 {
            let v = t[e];
            first_face.entry(key(v)).or_insert_with(|| {
                verts.push(v);
                vert_face.push(i);
                i
            });
            let (p, q) = (t[e], t[(e + 1) % 3]);
            let (a, b) = (key(p), key(q));
            let k = if a < b { (a, b) } else { (b, a) };
            edges.entry(k).or_insert_with(|| {
                total_len += (q - p).length();
                (p, q, i)
            });
        }
    }
    let h = total_len / edges.len().max(1) as f64;
    if h.is_nan() || h <= 0.0 || !h.is_finite() {
        return;
    }
    let tol = 1e-9 * scale;
    let cell = |p: DVec3| -> [i64; 3] { (p / h).floor().to_array().map(|x| x as i64) };
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, &v) in verts.iter().enumerate() {
        grid.entry(cell(v)).or_default().push(i);
    }
    let mut found: Vec<(usize, usize, DVec3)> = Vec::new();
    let mut sorted_edges: Vec<_> = edges.into_values().collect();
    sorted_edges.sort_by_key(|e| e.2);
    // The last edge each vertex was tested against: a vertex near many steps
    // of one edge is tested once, in constant time.
    let mut tested_for = vec![usize::MAX; verts.len()];
    for (e, (p, q, face)) in sorted_edges.into_iter().enumerate() {
        let d = q - p;
        let len2 = d.length_squared();
        let steps = ((len2.sqrt() / h).ceil() as usize).max(1);
        for s in 0..=steps {
            let c = cell(p + d * (s as f64 / steps as f64));
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                            continue;
                        };
                        for &vi in list {
                            if tested_for[vi] == e {
                                continue;
                            }
                            tested_for[vi] = e;
                            let v = verts[vi];
                            let t = (v - p).dot(d) / len2;
                            let off = (p + d * t - v).length();
                            let inside = t * len2.sqrt() > tol && (1.0 - t) * len2.sqrt() > tol;
                            if inside && off <= tol {
                                found.push((vert_face[vi], face, v));
                            }
                        }
                    }
                }
            }
        }
    }
    found.sort_by_key(|f| (f.1, f.0));
    let mut w = Capped::new(warnings, "T-junction");
    for (vf, ef, v) in found {
        w.push(format!(
            "T-junction: vertex ({:.6}, {:.6}, {:.6}) of the triangle at {} lies inside an edge of the triangle at {}",
            v.x, v.y, v.z, raw[vf].at, raw[ef].at
        ));
    }
}
