"""What one export by Caustic holds while Blender's exporter runs, read by the exporter's hooks:
the hooks stay out of the user's own glTF exports (`exporting`), and add what Caustic computed
before the exporter ran."""


class ExportState:
    def __init__(self):
        self.clear()

    def clear(self):
        # True only while Caustic exports.
        self.exporting = False
        # The world's extras (an environment image is written before the exporter runs, so that an
        # image that cannot be read stops the export with its name).
        self.world = None
        # The names of the objects rendered as holdouts (`extras.holdout_objects`).
        self.holdouts = set()
        # The objects replaced by a copy with their shape keys baked
        # (`workarounds.bake_shape_keys`): the exporter leaves them out.
        self.replaced = set()
        # The colour temperature (kelvin) of each light that uses one, by name: Blender's exporter
        # raises a TypeError on a light with `use_temperature`, so it is switched off for the
        # export and the temperature travels in the extras.
        self.temperatures = {}
        # What the export left out because Blender's exporter failed with it (`run_exporter`).
        self.fallbacks = []


STATE = ExportState()
