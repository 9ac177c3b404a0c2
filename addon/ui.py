"""Panels: the renderer's settings, dispersion and volume priority on materials, and Blender's own camera
depth-of-field, light, motion-blur, material and world panels shown for Caustic (they list their
engines explicitly, so a third-party engine must add itself)."""

import bpy

# Blender's panels that draw what Caustic reads (Blender 5.0 names; missing ones are skipped).
BLENDER_PANELS = (
    "DATA_PT_camera_dof", "DATA_PT_camera_dof_aperture", "DATA_PT_EEVEE_light", "RENDER_PT_eevee_motion_blur",
    "EEVEE_MATERIAL_PT_context_material", "EEVEE_MATERIAL_PT_surface", "EEVEE_WORLD_PT_surface",
    "RENDER_PT_eevee_film", "RENDER_PT_film",
)


class CausticPanel:
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    COMPAT_ENGINES = {'CAUSTIC'}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES


class RENDER_PT_caustic_sampling(CausticPanel, bpy.types.Panel):
    bl_label = "Caustic"
    bl_context = "render"

    def draw(self, context):
        settings = context.scene.caustic
        layout = self.layout
        layout.use_property_split = True
        layout.prop(settings, "passes")
        row = layout.row(heading="Time Budget")
        row.prop(settings, "use_time_budget", text="")
        row.prop(settings, "time_budget", text="")
        row = layout.row(heading="Target Error")
        row.prop(settings, "use_target_error", text="")
        row.prop(settings, "target_error", text="")
        layout.prop(settings, "method")
        layout.prop(settings, "photons")
        layout.prop(settings, "alpha")
        layout.prop(settings, "seed")
        layout.prop(settings, "threads")
        layout.prop(settings, "denoise")
        layout.prop(settings, "bake_size")


class MATERIAL_PT_caustic_glass(CausticPanel, bpy.types.Panel):
    bl_label = "Glass"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.material is not None

    def draw(self, context):
        settings = context.material.caustic
        layout = self.layout
        layout.use_property_split = True
        layout.prop(settings, "dispersion")
        if settings.dispersion == 'ABBE':
            layout.prop(settings, "abbe")
        elif settings.dispersion == 'GLASS':
            layout.prop(settings, "glass")
        layout.prop(settings, "priority")


CLASSES = (RENDER_PT_caustic_sampling, MATERIAL_PT_caustic_glass)


def blender_panels():
    return [panel for name in BLENDER_PANELS if (panel := getattr(bpy.types, name, None)) is not None]


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    for panel in blender_panels():
        panel.COMPAT_ENGINES.add('CAUSTIC')


def unregister():
    for panel in blender_panels():
        panel.COMPAT_ENGINES.discard('CAUSTIC')
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
