//! What the loader refuses before it reads: references outside the scene's folder, indices and
//! accessor types that the gltf crate would follow unchecked (and panic on), and accessors or
//! buffer views that reach past their data. Each refusal is a message naming what is wrong.

/// A message for the gltf crate's errors that says what the user must fix.
pub fn describe_import_error(error: gltf::Error) -> String {
    match error {
        gltf::Error::Io(e) => format!("cannot read the file or a file it references: {e}"),
        gltf::Error::Deserialize(e) => format!("not a valid glTF file (malformed JSON): {e}"),
        gltf::Error::Validation(errors) => {
            let list: Vec<String> = errors.iter().map(|(path, e)| format!("{path}: {e}")).collect();
            format!(
                "not a valid glTF 2.0 file (unsupported required extension or invalid field): {}",
                list.join("; ")
            )
        }
        gltf::Error::Base64(e) => format!("a buffer's data URI is not valid base64 ({e})"),
        other => format!("cannot load glTF: {other}"),
    }
}

/// Refuses indices that the gltf crate follows without checking (it would panic): mesh
/// primitives' accessors, and animation channels' samplers and nodes and samplers' accessors.
pub fn check_indices(root: &gltf::json::Root) -> Result<(), String> {
    check_mesh_accessor_indices(root)?;
    let (accessors, nodes) = (root.accessors.len(), root.nodes.len());
    for (a, animation) in root.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let (sampler, node) = (channel.sampler.value(), channel.target.node.value());
            if sampler >= animation.samplers.len() || node >= nodes {
                return Err(format!(
                    "animation {a} channel {c} names sampler {sampler} of {} and node {node} of {nodes}",
                    animation.samplers.len()
                ));
            }
            use gltf::json::accessor::{ComponentType as C, Type as T};
            use gltf::json::animation::Property as P;
            use gltf::json::validation::Checked::Valid;
            let (kind, components): (T, &[C]) = match &channel.target.path {
                Valid(P::Translation) | Valid(P::Scale) => (T::Vec3, &[C::F32]),
                Valid(P::Rotation) => (T::Vec4, &[C::F32, C::I8, C::U8, C::I16, C::U16]),
                _ => (T::Scalar, &[C::F32, C::I8, C::U8, C::I16, C::U16]),
            };
            let output = animation.samplers[sampler].output.value();
            if output < accessors && !accessor_is(root, output, kind, components) {
                return Err(format!(
                    "animation {a} channel {c}: its values have the wrong type for its target"
                ));
            }
        }
        for (i, sampler) in animation.samplers.iter().enumerate() {
            if let Some(bad) =
                [sampler.input.value(), sampler.output.value()].into_iter().find(|&x| x >= accessors)
            {
                return Err(format!(
                    "animation {a} sampler {i} names accessor {bad}, but the file has {accessors}"
                ));
            }
            if !accessor_is(
                root,
                sampler.input.value(),
                gltf::json::accessor::Type::Scalar,
                &[gltf::json::accessor::ComponentType::F32],
            ) {
                return Err(format!("animation {a} sampler {i}: its key times are not float scalars"));
            }
        }
    }
    Ok(())
}

/// Whether accessor `index` holds `kind` elements of one of `components` (the gltf crate's
/// readers assume so and panic otherwise).
fn accessor_is(
    root: &gltf::json::Root,
    index: usize,
    kind: gltf::json::accessor::Type,
    components: &[gltf::json::accessor::ComponentType],
) -> bool {
    use gltf::json::validation::Checked::Valid;
    let accessor = &root.accessors[index];
    matches!((&accessor.type_, &accessor.component_type), (Valid(t), Valid(c)) if *t == kind && components.contains(&c.0))
}

/// Refuses mesh primitives whose attributes, indices or morph targets name accessors that do not
/// exist, or whose positions, normals, texture coordinates or indices have the wrong type.
fn check_mesh_accessor_indices(root: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::accessor::{ComponentType as C, Type as T};
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked::Valid;
    let count = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let targets = primitive.targets.iter().flatten();
            let target_accessors = targets.flat_map(|t| [t.positions, t.normals, t.tangents]).flatten();
            let used =
                primitive.attributes.values().copied().chain(primitive.indices).chain(target_accessors);
            if let Some(bad) = used.map(|a| a.value()).find(|&a| a >= count) {
                return Err(format!(
                    "mesh {m} primitive {p} names accessor {bad}, but the file has {count} accessors"
                ));
            }
            let mut expected: Vec<(&str, usize, T, &[C])> = Vec::new();
            for (semantic, accessor) in &primitive.attributes {
                match semantic {
                    Valid(Semantic::Positions) => {
                        expected.push(("POSITION", accessor.value(), T::Vec3, &[C::F32]))
                    }
                    Valid(Semantic::Normals) => {
                        expected.push(("NORMAL", accessor.value(), T::Vec3, &[C::F32]))
                    }
                    Valid(Semantic::TexCoords(0)) => {
                        expected.push(("TEXCOORD_0", accessor.value(), T::Vec2, &[C::F32, C::U8, C::U16]))
                    }
                    _ => {}
                }
            }
            if let Some(indices) = primitive.indices {
                expected.push(("indices", indices.value(), T::Scalar, &[C::U8, C::U16, C::U32]));
            }
            for (what, accessor, kind, components) in expected {
                if !accessor_is(root, accessor, kind, components) {
                    return Err(format!(
                        "mesh {m} primitive {p}: its {what} accessor {accessor} has the wrong type (glTF wants {kind:?} of {components:?})"
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Refuses buffers and images that point outside the scene's folder: absolute paths, `..` that
/// climbs out of it, and URI schemes other than `data:`. A scene must not make the renderer read
/// arbitrary files.
pub fn check_references(document: &gltf::Document) -> Result<(), String> {
    check_image_sources(document.as_json())?;
    let buffers = document.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(uri) => Some((format!("buffer {}", b.index()), uri)),
        gltf::buffer::Source::Bin => None,
    });
    let images = document.images().filter_map(|i| match i.source() {
        gltf::image::Source::Uri { uri, .. } => Some((format!("image {}", i.index()), uri)),
        gltf::image::Source::View { .. } => None,
    });
    for (what, uri) in buffers.chain(images) {
        check_relative(uri).map_err(|why| format!("{what} refers to '{uri}': {why}"))?;
    }
    Ok(())
}

/// Refuses images that say neither where their data is (a `uri` or a `bufferView`) nor, in a
/// buffer view, what it holds (`mimeType`): the gltf crate's validation lets both through and
/// panics reading them.
fn check_image_sources(root: &gltf::json::Root) -> Result<(), String> {
    for (i, image) in root.images.iter().enumerate() {
        match (&image.buffer_view, &image.uri, &image.mime_type) {
            (Some(_), _, None) => return Err(format!("image {i} is in a buffer view but has no mimeType")),
            (None, None, _) => return Err(format!("image {i} has neither a uri nor a bufferView")),
            _ => {}
        }
    }
    Ok(())
}

/// Whether `reference` (a URI or path) stays inside the folder it is relative to.
pub fn check_relative(reference: &str) -> Result<(), String> {
    if reference.starts_with("data:") {
        return Ok(());
    }
    let decoded = reference.replace("%2e", ".").replace("%2E", ".").replace("%2f", "/").replace("%2F", "/");
    let absolute = decoded.starts_with(['/', '\\'])
        || decoded.contains("://")
        || decoded.as_bytes().get(1) == Some(&b':');
    if absolute {
        return Err("absolute paths and URLs are refused; use a path relative to the scene's folder".into());
    }
    let mut depth = 0i32;
    for part in decoded.split(['/', '\\']) {
        depth += match part {
            ".." => -1,
            "" | "." => 0,
            _ => 1,
        };
        if depth < 0 {
            return Err(
                "it leaves the scene's folder; keep referenced files beside the scene or below it".into()
            );
        }
    }
    Ok(())
}

/// Refuses accessors and buffer views that reach past the data they read (a count of 1e12, a
/// bad offset), before any of it is read.
/// Refuses a sparse accessor whose indices or values run past their buffer views, or that
/// replaces no element or more elements than the accessor has.
fn check_sparse(accessor: &gltf::Accessor, sparse: &gltf::accessor::sparse::Sparse) -> Result<(), String> {
    let (i, count) = (accessor.index(), sparse.count());
    if count == 0 || count > accessor.count() {
        return Err(format!(
            "accessor {i}: a sparse part of {count} elements in an accessor of {}",
            accessor.count()
        ));
    }
    let (indices, values) = (sparse.indices(), sparse.values());
    let parts = [
        ("indices", indices.view(), indices.offset(), indices.index_type().size()),
        ("values", values.view(), values.offset(), accessor.size()),
    ];
    for (what, view, offset, size) in parts {
        let end = count.checked_mul(size).and_then(|n| n.checked_add(offset));
        if end.is_none_or(|end| end > view.length()) {
            return Err(format!(
                "accessor {i}: its sparse {what} ({count} of {size} bytes from byte {offset}) run past buffer view {} ({} bytes)",
                view.index(),
                view.length()
            ));
        }
    }
    Ok(())
}

pub fn check_accessors(document: &gltf::Document, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    for view in document.views() {
        let available = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
        if view.offset().checked_add(view.length()).is_none_or(|end| end > available) {
            return Err(format!(
                "buffer view {} (bytes {} to {}) runs past buffer {} ({available} bytes)",
                view.index(),
                view.offset(),
                view.offset().saturating_add(view.length()),
                view.buffer().index()
            ));
        }
    }
    for accessor in document.accessors() {
        let count = accessor.count();
        if count == 0 {
            // glTF requires at least one element (and the gltf crate's reader underflows on none).
            return Err(format!("accessor {} has no elements (count 0)", accessor.index()));
        }
        if let Some(sparse) = accessor.sparse() {
            check_sparse(&accessor, &sparse)?;
        }
        let Some(view) = accessor.view() else { continue };
        let element = accessor.size();
        let stride = view.stride().unwrap_or(element);
        let end = (count - 1).checked_mul(stride).and_then(|n| n.checked_add(accessor.offset() + element));
        if end.is_none_or(|end| end > view.length()) {
            return Err(format!(
                "accessor {} ({count} elements from byte {}) runs past buffer view {} ({} bytes)",
                accessor.index(),
                accessor.offset(),
                view.index(),
                view.length()
            ));
        }
    }
    Ok(())
}
