// SPDX-License-Identifier: GPL-3.0-or-later
//
// Caustic on Flamenco (Blender's render-farm manager): a job compiler script. Copy it into the
// Manager's `scripts/` folder; Blender's Flamenco add-on then offers "Caustic" as a job type.
//
// One job renders a frame range in pass chunks:
//   1. export: Blender opens the .blend and writes the scene as Caustic reads it (glTF with the
//      `caustic` extras, through the Caustic add-on's `caustic.export_scene` operator);
//   2. render: for every chunk of frames and every chunk of passes, `caustic render --pass-range
//      A..B --partial` writes each frame's sums (frames of one task share paths on static
//      geometry); each depends on the export;
//   3. merge: per frame, `caustic merge` adds that frame's partial results into frame_####.exr
//      (exactly the whole run's image and error passes); each depends on that frame's renders.
// Passes are independent (Knaus & Zwicker's radius sequence), so chunks run on any worker in any
// order. Workers need Blender with the Caustic add-on enabled, and the `caustic` program.

const JOB_TYPE = {
    label: "Caustic",
    description: "Spectral progressive photon mapping, rendered in pass chunks and merged exactly",
    settings: [
        // Settings for artists:
        { key: "frames", type: "string", required: true,
          eval: "f'{C.scene.frame_start}-{C.scene.frame_end}'",
          evalInfo: { showLinkButton: true, description: "Scene frame range" },
          description: "Frames to render: '47', '1-30', '3, 5-10, 47-327'" },
        { key: "passes", type: "int32", default: 256, required: true,
          description: "Passes per frame" },
        { key: "pass_chunk", type: "int32", default: 64, required: true,
          description: "Passes rendered by one task" },
        { key: "frame_chunk", type: "int32", default: 1, required: true,
          description: "Frames rendered together by one task (they share paths on static geometry)" },
        { key: "seed", type: "int32", default: 1, description: "Random seed" },
        { key: "caustic_flags", type: "string", default: "",
          description: "More `caustic render` flags, e.g. '--photons 500000 --alpha 0.7'" },
        { key: "caustic", type: "string", default: "caustic", visible: "submission",
          description: "The caustic program on the workers" },

        // Automatically evaluated settings:
        { key: "blendfile", type: "string", required: true, visible: "web",
          description: "Path of the Blend file to render" },
        { key: "render_output_path", type: "string", subtype: "file_path", editable: false,
          eval: "str(Path(abspath(C.scene.render.filepath), jobname))",
          description: "Folder of the merged frames (frame_####.exr)" },
    ]
};

function compileJob(job) {
    const settings = job.settings;
    const frames = parseFrames(settings.frames);
    const folders = jobFolders(settings.render_output_path);

    const exportTask = authorExportTask(settings, folders);
    job.addTask(exportTask);

    const rendersOfFrame = new Map(frames.map(frame => [frame, []]));
    for (const frameChunk of chunks(frames, settings.frame_chunk)) {
        for (const [first, end] of passChunks(settings.passes, settings.pass_chunk)) {
            const task = authorRenderTask(settings, folders, frameChunk, first, end);
            task.addDependency(exportTask);
            job.addTask(task);
            for (const frame of frameChunk) {
                rendersOfFrame.get(frame).push({ task: task, file: partialFile(folders.partials, frame, first, end) });
            }
        }
    }
    for (const [frame, renders] of rendersOfFrame) {
        const task = authorMergeTask(settings, folders, frame, renders.map(r => r.file));
        for (const render of renders) {
            task.addDependency(render.task);
        }
        job.addTask(task);
    }
}

// Where a job keeps its scene, its partial results and its frames.
function jobFolders(output) {
    return {
        output: output,
        scene: path.join(output, "scene", "scene.gltf"),
        partials: path.join(output, "partials"),
    };
}

function authorExportTask(settings, folders) {
    const task = author.Task("export", "blender");
    const expr = `import bpy; bpy.ops.caustic.export_scene(filepath=${JSON.stringify(folders.scene)})`;
    task.addCommand(author.Command("blender-render", {
        exe: "{blender}",
        exeArgs: "{blenderArgs}",
        argsBefore: [],
        blendfile: settings.blendfile,
        args: ["--python-expr", expr],
    }));
    return task;
}

function authorRenderTask(settings, folders, frames, first, end) {
    const label = frames.length == 1 ? `${frames[0]}` : `${frames[0]}-${frames[frames.length - 1]}`;
    const task = author.Task(`render-${label}-passes-${first}-${end}`, "misc");
    const extra = settings.caustic_flags.split(" ").filter(arg => arg.length > 0);
    task.addCommand(author.Command("exec", {
        exe: settings.caustic,
        args: ["render", folders.scene, "--frames", frames.join(","), "--pass-range", `${first}..${end}`,
               "--partial", "--seed", `${settings.seed}`, "--progress", "none", "-o", folders.partials]
              .concat(extra),
    }));
    return task;
}

function authorMergeTask(settings, folders, frame, files) {
    const task = author.Task(`merge-${frame}`, "misc");
    task.addCommand(author.Command("exec", {
        exe: settings.caustic,
        args: ["merge"].concat(files, ["-o", folders.output]),
    }));
    return task;
}

// The partial result `caustic render --partial` writes (src/render/partial.rs, `partial_path`).
function partialFile(folder, frame, first, end) {
    return path.join(folder, `frame_${String(frame).padStart(4, "0")}.passes_${first}-${end}.partial`);
}

// [first, end) pass ranges of at most `chunk` passes covering 0..passes.
function passChunks(passes, chunk) {
    if (!(passes >= 1) || !(chunk >= 1)) {
        throw `passes (${passes}) and pass_chunk (${chunk}) must be at least 1`;
    }
    const ranges = [];
    for (let first = 0; first < passes; first += chunk) {
        ranges.push([first, Math.min(first + chunk, passes)]);
    }
    return ranges;
}

// Consecutive groups of at most `size` items.
function chunks(items, size) {
    const groups = [];
    for (let i = 0; i < items.length; i += Math.max(1, size)) {
        groups.push(items.slice(i, i + Math.max(1, size)));
    }
    return groups;
}

// The frames of '47', '1-30', '3, 5-10, 47-327', in order.
function parseFrames(spec) {
    const frames = [];
    for (const item of String(spec).split(",").map(s => s.trim()).filter(s => s.length > 0)) {
        const match = /^(\d+)(?:-(\d+))?$/.exec(item);
        if (!match) {
            throw `frames: cannot read '${item}' (expected numbers and ranges like 3, 5-10)`;
        }
        const first = parseInt(match[1]), last = match[2] === undefined ? first : parseInt(match[2]);
        if (last < first) {
            throw `frames: '${item}' ends before it starts`;
        }
        for (let frame = first; frame <= last; frame++) {
            frames.push(frame);
        }
    }
    if (frames.length == 0) {
        throw "frames: no frames to render";
    }
    return frames;
}
