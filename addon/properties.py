"""Settings Blender lacks: the renderer's settings on the scene, dispersion on materials, and the
path of the `caustic` program in the add-on's preferences."""

import os
import pathlib
import shutil

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

# The glasses of spectra/glasses.csv (what `caustic.glass` accepts in a material's extras).
GLASSES = [
    ("BK7", "BK7", "Schott N-BK7 crown glass (n_d 1.517, Abbe 64.2)"),
    ("fused_silica", "Fused silica", "Fused silica (n_d 1.458, Abbe 67.8)"),
    ("SF11", "SF11", "Schott N-SF11 dense flint (n_d 1.785, Abbe 25.7)"),
    ("water", "Water", "Water at 20 C (n_d 1.333, Abbe 55.8)"),
    ("diamond", "Diamond", "Diamond (n_d 2.417, Abbe 55.3)"),
    ("sapphire", "Sapphire", "Sapphire, ordinary ray (n_d 1.768, Abbe 72.3)"),
]


# The compositor node group the Denoise option makes when the scene has none.
DENOISE_GROUP = "Caustic Denoise"


def denoise_compositor(scene):
    """Makes the scene's compositor denoise the render with Blender's Denoise node (Open Image
    Denoise), guided by Caustic's Denoising Albedo and Denoising Normal passes, unless the scene
    has a compositor of its own. Returns whether the compositor denoises."""
    group = scene.compositing_node_group
    if group is not None:
        return any(node.type == 'DENOISE' for node in group.nodes)
    group = bpy.data.node_groups.get(DENOISE_GROUP) or make_denoise_group()
    scene.compositing_node_group = group
    scene.render.use_compositing = True
    return True


def compositor_denoises(scene):
    """Whether Blender's compositor runs a Denoise node on the render."""
    group = scene.compositing_node_group
    return scene.render.use_compositing and group is not None and any(n.type == 'DENOISE' for n in group.nodes)


def make_denoise_group():
    """Render Layers (Image, Denoising Albedo, Denoising Normal) into a Denoise node (HDR) into
    the group's Image output."""
    group = bpy.data.node_groups.new(DENOISE_GROUP, "CompositorNodeTree")
    group.interface.new_socket("Image", in_out='OUTPUT', socket_type='NodeSocketColor')
    layers, denoise = group.nodes.new("CompositorNodeRLayers"), group.nodes.new("CompositorNodeDenoise")
    output = group.nodes.new("NodeGroupOutput")
    layers.location, denoise.location, output.location = (-300, 0), (0, 0), (250, 0)
    denoise.inputs["HDR"].default_value = True
    group.links.new(layers.outputs["Image"], denoise.inputs["Image"])
    group.links.new(layers.outputs["Denoising Albedo"], denoise.inputs["Albedo"])
    group.links.new(layers.outputs["Denoising Normal"], denoise.inputs["Normal"])
    group.links.new(denoise.outputs["Image"], output.inputs["Image"])
    return group


def denoise_changed(settings, context):
    if settings.denoise:
        denoise_compositor(settings.id_data)


class CausticRenderSettings(bpy.types.PropertyGroup):
    """`scene.caustic`: the flags of `caustic render`."""

    passes: IntProperty(name="Passes", default=64, min=1, max=1_000_000,
                        description="Passes per frame (each pass: one wavelength, one photon map)")
    use_time_budget: BoolProperty(name="Time Budget", default=False,
                                  description="End each frame after this many seconds instead")
    time_budget: FloatProperty(name="Seconds", default=60.0, min=0.1, unit='TIME_ABSOLUTE',
                               description="Wall-clock seconds per frame")
    use_target_error: BoolProperty(name="Target Error", default=False,
                                   description="End each frame when its mean relative error bound is below this")
    target_error: FloatProperty(name="Error", default=0.05, min=0.001, max=10.0,
                                description="Mean relative error bound (90% confidence) at which a frame ends")
    photons: IntProperty(name="Photons per Pass", default=0, min=0,
                         description="Photon paths per pass (0: one per pixel)")
    method: EnumProperty(
        name="Method",
        items=[("SPPM", "Photon Mapping", "Stochastic progressive photon mapping: photons gathered where each pixel's "
                                          "path first meets a diffuse surface"),
               ("VCM", "Connection and Merging", "Vertex connection and merging: photon merging where photon mapping gathers, "
                                                 "combined with path tracing, light tracing and connections (not yet "
                                                 "for fog that scatters)")],
        default="SPPM", description="How each pass combines camera paths and photon paths")
    alpha: FloatProperty(name="Alpha", default=0.0, min=0.0, max=0.99,
                         description="How fast the gather radius shrinks (Knaus & Zwicker); 0: the method's own "
                                     "(2/3 for Photon Mapping, 0.8 for Connection and Merging)")
    seed: IntProperty(name="Seed", default=1, min=0, description="The same seed gives the same image")
    threads: IntProperty(name="Threads", default=0, min=0, max=256, description="Worker threads (0: all cores)")
    bake_size: IntProperty(name="Bake Size", default=512, min=16, max=8192, subtype='PIXEL',
                           description="Width and height of the images Blender bakes of material inputs glTF "
                                       "cannot hold (procedural textures, ColorRamp, Mix nodes)")
    denoise: BoolProperty(name="Denoise", default=False, update=denoise_changed,
                          description="Write the Denoising Albedo and Denoising Normal passes and denoise the render "
                                      "with Blender's Denoise node (Open Image Denoise) in the compositor (set up "
                                      "when the scene has no compositor of its own)")


class CausticMaterialSettings(bpy.types.PropertyGroup):
    """`material.caustic`: how a glass's index of refraction depends on wavelength, and which
    volume fills where two overlap."""

    dispersion: EnumProperty(
        name="Dispersion",
        items=[("NONE", "None", "The index is the same at every wavelength"),
               ("ABBE", "Abbe Number", "The material's IOR at 587.6 nm with an Abbe number"),
               ("GLASS", "Glass", "A measured glass from the catalogue")],
        default="NONE")
    abbe: FloatProperty(name="Abbe Number", default=40.0, min=1.0, max=200.0,
                        description="Abbe number V_d: lower disperses more (flint glass about 30, crown about 60)")
    glass: EnumProperty(name="Glass", items=GLASSES, default="BK7")
    priority: IntProperty(name="Volume Priority", default=0, min=-1000, max=1000,
                          description="Where this glass's volume overlaps another's (water modelled into its glass's "
                                      "wall, ice in water), the volume of highest priority fills the overlap")


def repository_binaries():
    """`caustic` built in the repository this add-on was installed from, newest build kind first."""
    root = pathlib.Path(__file__).resolve().parent.parent
    return [root / "target" / kind / "caustic" for kind in ("release", "debug")]


def bundled_binary():
    """The `caustic` program the installed zip carries (`bin/caustic`, tools/build_addon.py), made
    executable where unpacking lost its mode; None where the add-on carries none."""
    path = pathlib.Path(__file__).resolve().parent / "bin" / "caustic"
    if not path.is_file():
        return None
    if not os.access(path, os.X_OK):
        path.chmod(path.stat().st_mode | 0o755)
    return str(path)


def find_binary(preferences_path):
    """The `caustic` program to run: the preference if set, else the one the add-on carries, else
    on PATH, else built in the repository. Returns (path, None) or (None, what went wrong)."""
    if preferences_path:
        path = bpy.path.abspath(preferences_path)
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path, None
        return None, f"the caustic program set in the add-on's preferences is not an executable file: {path}"
    found = (bundled_binary() or shutil.which("caustic")
             or next((str(p) for p in repository_binaries() if p.is_file()), None))
    if found:
        return found, None
    return None, ("cannot find the caustic program: put it on PATH, build it with `cargo build --release`, "
                  "or set its path in the add-on's preferences")


class CausticPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    binary: StringProperty(name="caustic Program", subtype='FILE_PATH', default="",
                           description="Path of the caustic program (empty: found on PATH or in the repository)")

    def draw(self, context):
        self.layout.prop(self, "binary")
        path, problem = find_binary(self.binary)
        self.layout.label(text=f"Using {path}" if path else problem, icon='CHECKMARK' if path else 'ERROR')


CLASSES = (CausticRenderSettings, CausticMaterialSettings, CausticPreferences)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.caustic = PointerProperty(type=CausticRenderSettings)
    bpy.types.Material.caustic = PointerProperty(type=CausticMaterialSettings)


def unregister():
    del bpy.types.Material.caustic
    del bpy.types.Scene.caustic
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
