"""Volumes: a glass's Volume Absorption as `KHR_materials_volume`, a volume that scatters as a
`caustic` medium, and what of a volume node Caustic does not render."""

import math

from .nodes import surface_node, volume_node, world_volume_node


def volume_absorption(material):
    """The absorption of the material's volume (a Volume Absorption node, or a Principled Volume's
    absorption) as `KHR_materials_volume`'s attenuation colour and distance, or None where nothing
    absorbs. Converted exactly: Cycles absorbs `k = (1 - Color) * Density` per unit of length (a
    Principled Volume `(1 - Color)(1 - sqrt(Absorption Color)) * Density`, each factor at least 0),
    and glTF keeps `attenuationColor ^ (length / attenuationDistance)`; so the distance is
    `1 / Density` and each channel of the colour `exp(-k / Density)`. (Blender's glTF exporter
    writes the Color itself as the attenuation colour, which absorbs differently.)"""
    node = volume_node(material)
    if node is None or node.type not in ('VOLUME_ABSORPTION', 'PRINCIPLED_VOLUME'):
        return None
    colour = [max(c, 0.0) for c in node.inputs["Color"].default_value[:3]]
    density = node.inputs["Density"].default_value
    per_density = [max(1.0 - c, 0.0) for c in colour]
    if node.type == 'PRINCIPLED_VOLUME':
        absorption = node.inputs["Absorption Color"].default_value[:3]
        per_density = [k * max(1.0 - math.sqrt(max(a, 0.0)), 0.0) for k, a in zip(per_density, absorption)]
    if density <= 0.0 or max(per_density) <= 0.0:
        return None
    return {"attenuationColor": [math.exp(-k) for k in per_density], "attenuationDistance": 1.0 / density}


def volume_medium(node):
    """A volume node that scatters (a Volume Scatter, or a Principled Volume of some colour and
    density) as a `caustic` medium, converted as Cycles defines it: a Volume Scatter scatters
    `Color * Density` per unit of length and absorbs nothing; a Principled Volume scatters
    `Color * Density` and absorbs `(1 - Color)(1 - sqrt(Absorption Color)) * Density` (each factor
    at least 0); both with Henyey-Greenstein's anisotropy. None for other nodes and where nothing
    scatters (a Volume Absorption travels as KHR_materials_volume, exactly)."""
    if node is None or node.type not in ('VOLUME_SCATTER', 'PRINCIPLED_VOLUME'):
        return None
    colour = [max(c, 0.0) for c in node.inputs["Color"].default_value[:3]]
    density = max(node.inputs["Density"].default_value, 0.0)
    scattering = [c * density for c in colour]
    if max(scattering) <= 0.0:
        return None
    absorption = [0.0, 0.0, 0.0]
    if node.type == 'PRINCIPLED_VOLUME':
        tint = node.inputs["Absorption Color"].default_value[:3]
        absorption = [max(1.0 - c, 0.0) * max(1.0 - math.sqrt(max(a, 0.0)), 0.0) * density
                      for c, a in zip(colour, tint)]
    anisotropy = min(max(node.inputs["Anisotropy"].default_value, -0.99), 0.99)
    return {"absorption": absorption, "scattering": scattering, "anisotropy": anisotropy}


def add_volume(gltf_material, material):
    """Writes the material's volume: one that scatters as a `caustic` medium (with a clear
    boundary of index 1 where the material has no surface, as a Blender volume object has none),
    one that only absorbs as `KHR_materials_volume`, keeping the thickness factor the exporter
    wrote (from a glTF Material Output node) or 1 (glTF reads 0 as no volume; the factor matters
    only on open meshes, which render as thin walls of that thickness)."""
    from io_scene_gltf2.io.com.gltf2_io_extensions import Extension
    extensions = gltf_material.extensions or {}
    medium = volume_medium(volume_node(material))
    if medium is not None:
        extras = gltf_material.extras if isinstance(gltf_material.extras, dict) else {}
        gltf_material.extras = {**extras, "caustic": {**extras.get("caustic", {}), "medium": medium}}
        extensions.pop("KHR_materials_volume", None)
        if surface_node(material) is None:
            extensions["KHR_materials_transmission"] = Extension(
                "KHR_materials_transmission", {"transmissionFactor": 1.0}, required=False)
            extensions["KHR_materials_ior"] = Extension("KHR_materials_ior", {"ior": 1.0}, required=False)
            pbr = gltf_material.pbr_metallic_roughness
            if pbr is not None:
                pbr.base_color_factor, pbr.metallic_factor, pbr.roughness_factor = [1.0, 1.0, 1.0, 1.0], 0.0, 0.0
        gltf_material.extensions = extensions
        return
    absorption = volume_absorption(material)
    if absorption is None:
        return
    written = extensions.get("KHR_materials_volume")
    thickness = written.extension.get("thicknessFactor", 1.0) if written is not None else 1.0
    extension = {**absorption, "thicknessFactor": thickness}
    extensions["KHR_materials_volume"] = Extension("KHR_materials_volume", extension, required=False)
    gltf_material.extensions = extensions


def volume_node_warnings(node, name):
    """What of the volume node `node` (feeding `name`, a material or the world) Caustic does not
    render, as sentences."""
    if node.type not in ('VOLUME_ABSORPTION', 'VOLUME_SCATTER', 'PRINCIPLED_VOLUME'):
        return [f"{name}: its volume ({node.name}) is not rendered (Volume Absorption, Volume Scatter and a "
                "Principled Volume are)"]
    warnings = [f"{name}: the volume's {socket.name} is linked; its unlinked value is rendered"
                for socket in node.inputs
                if socket.name in ("Color", "Density", "Absorption Color", "Anisotropy") and socket.is_linked]
    if node.type == 'VOLUME_SCATTER' and node.phase != 'HENYEY_GREENSTEIN':
        warnings.append(f"{name}: the Volume Scatter's {node.phase.replace('_', '-').title()} phase is rendered as "
                        "Henyey-Greenstein of its Anisotropy")
    if node.type == 'PRINCIPLED_VOLUME':
        glows = node.inputs["Emission Strength"].default_value > 0 or node.inputs["Blackbody Intensity"].default_value > 0
        if glows:
            warnings.append(f"{name}: the Principled Volume's emission and blackbody are not rendered")
    if node.type in ('VOLUME_SCATTER', 'PRINCIPLED_VOLUME') and abs(node.inputs["Anisotropy"].default_value) > 0.99:
        warnings.append(f"{name}: the volume's Anisotropy is rendered at 0.99 (Henyey-Greenstein needs |g| < 1)")
    return warnings


def world_volume_warnings(world):
    """What of the world's volume Caustic does not render, as sentences."""
    node = world_volume_node(world)
    return [] if node is None else volume_node_warnings(node, f"world '{world.name}'")


def volume_warnings(material):
    """What of `material`'s volume Caustic does not render, as sentences."""
    node = volume_node(material)
    return [] if node is None else volume_node_warnings(node, f"material '{material.name}'")
