"""Caustic as a Blender render engine: export once, run one `caustic render` for the frames of the
render job (all of them under Render Animation: reuse across frames needs one process), follow its
progress, load each frame's EXR into the render result, and report every failure.

Blender calls `render()` once per frame. Under Render Animation the first call exports the scene and
starts the process for the whole frame range; each call then waits for its own frame's EXR.
"""

import pathlib
import shutil
import tempfile

import bpy

from . import export, extras, unrendered
from .process import RenderProcess
from .properties import compositor_denoises, find_binary


# Cycles' denoising passes, which Caustic writes with the Denoise option: name, channels, kind.
DENOISING_PASSES = (("Denoising Albedo", "RGB", 'COLOR'), ("Denoising Normal", "XYZ", 'VECTOR'))


class CausticError(Exception):
    """A failure to show the user as is."""


def frame_spec(frames):
    """`--frames` for a list of frames: a range with a step where it is one, else a list."""
    if len(frames) > 1 and all(b - a == frames[1] - frames[0] for a, b in zip(frames, frames[1:])):
        return f"{frames[0]}-{frames[-1]}:{frames[1] - frames[0]}"
    return ",".join(str(f) for f in frames)


def render_flags(scene):
    """`caustic render` flags from the scene's Caustic settings and its render region."""
    settings = scene.caustic
    flags = ["--passes", str(settings.passes), "--seed", str(settings.seed)]
    if settings.alpha > 0.0:
        flags += ["--alpha", repr(settings.alpha)]
    if settings.denoise:
        flags.append("--denoising-passes")
    region = extras.render_region(scene)
    if region is not None:
        x, y, width, height = region
        top = extras.resolution(scene)[1] - (y + height)
        flags += ["--crop", f"{x},{top},{width},{height}"]
    if settings.use_time_budget:
        flags += ["--time-budget", repr(settings.time_budget)]
    if settings.use_target_error:
        flags += ["--target-error", repr(settings.target_error)]
    if settings.photons > 0:
        flags += ["--photons", str(settings.photons)]
    if settings.method == 'VCM':
        flags += ["--method", "vcm"]
    if settings.threads > 0:
        flags += ["--threads", str(settings.threads)]
    return flags


def percent(error):
    """A relative error as a percentage: 0.034 is "3.4%"."""
    return f"{error * 100:.2f}".rstrip("0").rstrip(".") + "%"


def progress_line(event):
    """The status line for a progress event: the frames, the pass, the error and, with a target
    error, the time the renderer forecasts to reach it."""
    passes = event.get("passes")
    frames = event.get("frames", [event["frame"]])
    label = f"frame {frames[0]}" if len(frames) == 1 else f"frames {frames[0]}-{frames[-1]}"
    line = f"Caustic: {label}, pass {event['pass']}" + (f"/{passes}" if passes else "")
    if event.get("error") is not None:
        line += f", error {percent(event['error'])}"
    if event.get("target_error") is not None:
        left = event.get("seconds_left")
        line += f", {percent(event['target_error'])} " + (f"in about {left:.0f} s" if left is not None else "targeted")
    return line


def progress_fraction(event):
    """How far the frame is: its passes done of its pass count, or (without one) its time so far
    of the forecast time to the target error; None when neither is known."""
    if event.get("passes"):
        return min(1.0, event["pass"] / event["passes"])
    if event.get("seconds_left") is not None:
        return event["elapsed_s"] / max(event["elapsed_s"] + event["seconds_left"], 1e-9)
    return None


def cancelled(engine):
    """Whether the user pressed Esc (one place to ask, which the tests stand in for)."""
    return engine.test_break()


class Session:
    """One export and one renderer process for the frames of a render job."""

    def __init__(self, scene, frames, binary_preference):
        if min(frames) < 0:
            raise CausticError("Caustic renders frames numbered 0 and up; the frame range starts below 0")
        binary, problem = find_binary(binary_preference)
        if problem:
            raise CausticError(problem)
        self.frames = frames
        self.folder = pathlib.Path(tempfile.mkdtemp(prefix="caustic-"))
        scene_path = self.folder / "scene.gltf"
        try:
            self.export_s = export.export(scene, scene_path)
        except RuntimeError as error:
            self.close()
            raise CausticError(f"cannot export the scene to glTF: {error}") from error
        args = [binary, "render", str(scene_path), "-o", str(self.folder / "frames"), "--frames",
                frame_spec(frames), "--progress", "json", *render_flags(scene)]
        self.process = RenderProcess(args)
        self.written = {}

    def wait_for(self, engine, frame):
        """The EXR of `frame` once it is written, or None when the user cancels."""
        while frame not in self.written:
            if cancelled(engine):
                self.close()
                return None
            for event in self.process.events(timeout_s=0.1):
                self.follow(engine, event)
            if frame not in self.written and self.process.exit_code() is not None:
                # Lines still queued when the process ended come first.
                for event in self.process.events(timeout_s=0.0):
                    self.follow(engine, event)
                if frame not in self.written:
                    message = self.process.error_message()
                    self.close()
                    raise CausticError(message)
        return self.written[frame]

    def follow(self, engine, event):
        """Shows a progress line, or notes a written frame."""
        if "written" in event:
            self.written[event["frame"]] = event["written"]
        elif "pass" in event:
            engine.update_stats("", progress_line(event))
            fraction = progress_fraction(event)
            if fraction is not None:
                engine.update_progress(fraction)

    def close(self):
        """Ends the process (if it still runs), closes its pipes, and deletes the exported scene
        and frames."""
        if getattr(self, "process", None) is not None:
            self.process.stop()
        shutil.rmtree(self.folder, ignore_errors=True)


# The session of the render job in progress (Render Animation spans several `render()` calls).
_session = None


def close_session():
    global _session
    if _session is not None:
        _session.close()
        _session = None


def session_for(engine, scene):
    """The session that renders the current frame: the running animation's, or a new one."""
    global _session
    frame = scene.frame_current
    if engine.is_animation and _session is not None and frame in _session.frames:
        return _session
    close_session()
    frames = list(range(scene.frame_start, scene.frame_end + 1, scene.frame_step)) if engine.is_animation else []
    preferences = bpy.context.preferences.addons[__package__].preferences
    _session = Session(scene, frames if frame in frames else [frame], preferences.binary)
    return _session


class CausticRenderEngine(bpy.types.RenderEngine):
    """Spectral progressive photon mapping (the `caustic` program)."""

    bl_idname = "CAUSTIC"
    bl_label = "Caustic"
    bl_use_preview = False
    bl_use_postprocess = True

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", 'COLOR')
        self.register_pass(scene, renderlayer, "Error", 1, "Y", 'VALUE')
        if scene is not None and scene.caustic.denoise:
            for name, channels, kind in DENOISING_PASSES:
                self.register_pass(scene, renderlayer, name, len(channels), channels, kind)

    def render(self, depsgraph):
        # An exception escaping render() is swallowed by Blender, which then saves a blank image:
        # every failure is reported instead, so that the render fails visibly with its reason.
        try:
            self.render_frame(depsgraph)
        except CausticError as error:
            close_session()
            self.report({'ERROR'}, f"Caustic: {error}")
        except Exception as error:  # noqa: BLE001 - anything else is a bug, but must not be silent
            close_session()
            self.report({'ERROR'}, f"Caustic: unexpected failure: {error!r}")
            raise

    def render_frame(self, depsgraph):
        scene = depsgraph.scene
        session = session_for(self, scene)
        if session.written == {} and scene.frame_current == session.frames[0]:
            for warning in unrendered.scene_warnings(depsgraph):
                self.report({'WARNING'}, f"Caustic: {warning}")
            if scene.caustic.denoise and not compositor_denoises(scene):
                self.report({'WARNING'}, "Caustic: Denoise is on, but the scene's compositor has no Denoise node "
                                         "(or compositing is off): add one fed by Denoising Albedo and Normal")
        path = session.wait_for(self, scene.frame_current)
        if path is None:
            return
        self.load(scene, path)
        for warning in session.process.new_warnings():
            self.report({'WARNING'}, warning)
        if scene.frame_current == session.frames[-1]:
            close_session()

    def load(self, scene, path):
        """Puts the frame's EXR (Combined and Error) into the render result: the whole image, or
        the render region's window (Blender's result is then the region's, which Blender places
        in the image unless it is cropped to it)."""
        region = extras.render_region(scene)
        width, height = extras.resolution(scene) if region is None else region[2:]
        self.add_pass("Error", 1, "Y")
        if scene.caustic.denoise:
            for name, channels, _ in DENOISING_PASSES:
                self.add_pass(name, len(channels), channels)
        result = self.begin_result(0, 0, width, height)
        result.layers[0].load_from_file(path)
        self.end_result(result)
