//! What a glTF file's buffers hold: the buffers read (never outside the
//! scene's directory, never past their `byteLength`), and the accessors of
//! a primitive checked before the gltf crate's reader reads them.

use super::SceneError;
use std::path::Path;

/// The data of every buffer of `doc` (read from `path`, with the GLB's
/// binary chunk `blob`): an embedded `data:` URI decoded, a file beside the
/// scene read up to the buffer's `byteLength` and no further. A file that
/// is not a regular file (a device, a pipe), lies outside the scene's
/// directory, is shorter than its `byteLength`, or whose name does not
/// decode to UTF-8 is refused, naming the buffer.
pub(super) fn read_buffers(
    doc: &gltf::Document,
    path: &Path,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>, String> {
    use std::io::Read;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    let dir = std::fs::canonicalize(dir.unwrap_or(Path::new("."))).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    for b in doc.buffers() {
        let (i, need) = (b.index(), b.length());
        let bad = |m: String| format!("buffer {i}: {m}");
        let mut data = match b.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| bad("the GLB has no binary chunk".into()))?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                data_uri(uri).map_err(&bad)?
            }
            gltf::buffer::Source::Uri(uri) => {
                let file = buffer_file(uri, &dir).map_err(&bad)?;
                let mut data = Vec::with_capacity(need.min(1 << 30));
                std::fs::File::open(&file)
                    .and_then(|f| f.take(need as u64).read_to_end(&mut data))
                    .map_err(|e| bad(format!("{}: {e}", file.display())))?;
                data
            }
        };
        if data.len() < need {
            return Err(bad(format!(
                "{} bytes, where its byteLength says {need}",
                data.len()
            )));
        }
        while data.len() % 4 != 0 {
            data.push(0);
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes of a base64 `data:` URI (the only kind glTF allows for
/// buffers: `data:application/octet-stream;base64,…`).
fn data_uri(uri: &str) -> Result<Vec<u8>, String> {
    use base64::Engine;
    let head = |u: &str| u.chars().take(48).collect::<String>();
    let (meta, payload) = uri
        .split_once(',')
        .ok_or_else(|| format!("data URI {:?}… has no ','", head(uri)))?;
    if !meta.ends_with(";base64") {
        return Err(format!("data URI {:?}… is not base64", head(uri)));
    }
    base64::engine::general_purpose::STANDARD
        .decode(payload)
        .map_err(|e| format!("data URI: {e}"))
}

/// The regular file inside the scene's directory `dir` (canonical) that
/// the buffer URI `uri` names (relative and percent-encoded, or `file:`).
fn buffer_file(uri: &str, dir: &Path) -> Result<std::path::PathBuf, String> {
    let named = if let Some(rest) = uri.strip_prefix("file://").or(uri.strip_prefix("file:")) {
        std::path::PathBuf::from(rest)
    } else if uri.contains(':') {
        return Err(format!("URI {uri:?}: only data: URIs and files are read"));
    } else {
        let decoded = urlencoding::decode(uri)
            .map_err(|_| format!("URI {uri:?} does not decode to UTF-8 text"))?;
        dir.join(&*decoded)
    };
    let file = std::fs::canonicalize(&named).map_err(|e| format!("{}: {e}", named.display()))?;
    if !file.starts_with(dir) {
        return Err(format!(
            "URI {uri:?} names {}, outside the scene's directory {}",
            file.display(),
            dir.display()
        ));
    }
    if !std::fs::metadata(&file).is_ok_and(|m| m.is_file()) {
        return Err(format!(
            "{} is not a regular file (a device, a pipe or a directory)",
            file.display()
        ));
    }
    Ok(file)
}

/// Refuses the accessors of `prim` that the gltf crate's reader would
/// read wrongly (as no indices), or assert on: positions that are not
/// three floats, indices that are not unsigned integers, an element
/// wider than its view's byteStride, an index view with a byteStride,
/// and elements past the end of their view or of its buffer.
pub(super) fn check_accessors(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    at: &str,
) -> Result<(), SceneError> {
    use gltf::accessor::{DataType, Dimensions};
    let bad = |message: String| SceneError::Syntax {
        at: at.to_string(),
        message,
    };
    let position = prim.get(&gltf::Semantic::Positions);
    let mut checked: Vec<(gltf::Accessor, &str)> = Vec::new();
    if let Some(p) = position {
        if p.data_type() != DataType::F32 || p.dimensions() != Dimensions::Vec3 {
            return Err(bad(format!(
                "POSITION (accessor {}) is {:?} {:?}, not three floats",
                p.index(),
                p.dimensions(),
                p.data_type()
            )));
        }
        checked.push((p, "POSITION"));
    }
    if let Some(ix) = prim.indices() {
        let unsigned = matches!(ix.data_type(), DataType::U8 | DataType::U16 | DataType::U32);
        if !unsigned || ix.dimensions() != Dimensions::Scalar {
            return Err(bad(format!(
                "the indices (accessor {}) are {:?} {:?}, not unsigned integers",
                ix.index(),
                ix.dimensions(),
                ix.data_type()
            )));
        }
        if let Some(s) = ix.view().and_then(|v| v.stride()) {
            return Err(bad(format!(
                "the indices' buffer view has a byteStride ({s}), which glTF forbids for indices"
            )));
        }
        checked.push((ix, "the indices"));
    }
    for (a, what) in checked {
        let Some(view) = a.view() else {
            return Err(bad(format!(
                "{what} (accessor {}) has no buffer view (sparse-only accessors are not read)",
                a.index()
            )));
        };
        let size = a.size();
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(bad(format!(
                "{what}: buffer view {} has a byteStride of {stride}, less than its {size}-byte elements",
                view.index()
            )));
        }
        let end = a.offset() + stride * a.count().saturating_sub(1) + size;
        if a.count() > 0 && end > view.length() {
            return Err(bad(format!(
                "{what} (accessor {}, {} elements) run to byte {end} of buffer view {}, which holds {}",
                a.index(),
                a.count(),
                view.index(),
                view.length()
            )));
        }
        let held = buffers.get(view.buffer().index()).map_or(0, Vec::len);
        if view.offset() + view.length() > held {
            return Err(bad(format!(
                "buffer view {} runs to byte {} of buffer {}, which holds {held}",
                view.index(),
                view.offset() + view.length(),
                view.buffer().index()
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::data_uri;

    #[test]
    fn data_uris_are_base64_or_refused() {
        let ok = data_uri("data:application/octet-stream;base64,AAEC/w==");
        assert_eq!(ok.unwrap(), vec![0, 1, 2, 255]);
        let gltf_buffer = data_uri("data:application/gltf-buffer;base64,AAEC");
        assert_eq!(gltf_buffer.unwrap(), vec![0, 1, 2]);
        assert!(data_uri("data:application/octet-stream,abc")
            .unwrap_err()
            .contains("not base64"));
        assert!(data_uri("data:application/octet-stream;base64").is_err());
        assert!(data_uri("data:;base64,!!!!").is_err());
    }
}
