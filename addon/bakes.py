"""Inputs glTF cannot hold, baked by Blender into images: a separate Blender runs a bake script
(a bake cannot start inside a render) and the material reads the image for the export."""

import json
import pathlib
import shutil
import subprocess
import sys
import tempfile

import bpy

from .nodes import principled_node, unexported_nodes
from .state import STATE


def run_blender_script(script, arguments):
    """Runs `script` (beside this file) in a separate Blender, with `arguments` after "--"."""
    path = pathlib.Path(__file__).resolve().parent / script
    if bpy.app.binary_path:
        command = [bpy.app.binary_path, "--background", "--factory-startup", "--python", str(path), "--", *arguments]
    else:  # Blender as a Python module: its Python imports bpy
        command = [sys.executable, str(path), "--", *arguments]
    return subprocess.run(command, capture_output=True, text=True)


def last_line(done):
    """The last line a finished process printed, for messages."""
    return ((done.stderr or done.stdout).strip().splitlines()[-1:] or ["no output"])[0]


# The Principled inputs that are baked where nodes glTF cannot hold feed them.
BAKED_INPUTS = ("Base Color", "Metallic", "Roughness", "Emission Color", "Normal")


def procedural_bakes(scene):
    """(object, material, input) for each Principled input of BAKED_INPUTS fed through nodes glTF
    cannot hold, on the first mesh with texture coordinates that uses its material."""
    found, seen = [], set()
    for obj in scene.objects:
        if obj.type != 'MESH' or not obj.data.uv_layers:
            continue
        for material in {slot.material for slot in obj.material_slots if slot.material is not None}:
            surface = principled_node(material)
            if surface is None or material.name in seen:
                continue
            inputs = [name for name in BAKED_INPUTS if unexported_nodes(surface.inputs[name])]
            if inputs:
                seen.add(material.name)
                found += [(obj, material, name) for name in inputs]
    return found


def bake_procedural_inputs(scene):
    """Bakes the inputs `procedural_bakes` finds into images (in a separate Blender:
    bake_inputs.py) at the scene's Bake Size, and feeds each input its image for the export.
    Returns the steps that restore the materials."""
    jobs = procedural_bakes(scene)
    if not jobs:
        return []
    folder = pathlib.Path(tempfile.mkdtemp(prefix="caustic-bake-"))
    blend = folder / "objects.blend"
    bpy.data.libraries.write(str(blend), {obj for obj, _, _ in jobs}, fake_user=True, path_remap='ABSOLUTE')
    size = scene.caustic.bake_size
    listed = [{"object": obj.name, "material": material.name, "input": name, "out": str(folder / f"{i}.png"),
               "size": size} for i, (obj, material, name) in enumerate(jobs)]
    (folder / "jobs.json").write_text(json.dumps(listed))
    done = run_blender_script("bake_inputs.py", [str(blend), str(folder / "jobs.json")])
    undo = [lambda: shutil.rmtree(folder, ignore_errors=True)]
    if done.returncode != 0:
        STATE.fallbacks.append(f"Blender could not bake the material inputs glTF cannot hold: {last_line(done)}")
        return undo
    return undo + [use_image(material, name, job["out"]) for job, (_, material, name) in zip(listed, jobs)]


def use_image(material, name, path):
    """Feeds the Principled input `name` of `material` the image at `path` (linear values; for the
    Normal, a tangent-space normal map through a Normal Map node) in place of what fed it; returns
    the step that puts the original link back."""
    tree = material.node_tree
    socket = principled_node(material).inputs[name]
    original = socket.links[0].from_socket
    image = bpy.data.images.load(path)
    image.colorspace_settings.name = 'Non-Color'
    added = [tree.nodes.new("ShaderNodeTexImage")]
    added[0].image = image
    if name == "Normal":
        added.append(tree.nodes.new("ShaderNodeNormalMap"))
        tree.links.new(added[0].outputs["Color"], added[1].inputs["Color"])
    tree.links.new(added[-1].outputs[0], socket)

    def restore():
        for node in added:
            tree.nodes.remove(node)
        tree.links.new(original, socket)
        bpy.data.images.remove(image)
    return restore
