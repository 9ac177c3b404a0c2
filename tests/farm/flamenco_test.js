// The Flamenco job type (farm/flamenco/caustic.js), compiled against a stand-in for the job
// compiler API that Flamenco documents (JOB_TYPE settings; author.Task, author.Command,
// task.addCommand, task.addDependency, job.addTask; path; print), then run: its tasks execute in
// dependency order on this machine with the real `caustic` (the Blender export task is checked,
// not run: the scene is put where it would write it), and the merged frames must equal a single
// render of the same passes, frame by frame as the tasks render them (`--no-reuse`), byte for byte.
//
//     CAUSTIC_BINARY=target/debug/caustic node tests/farm/flamenco_test.js

"use strict";
const assert = require("node:assert/strict");
const childProcess = require("node:child_process");
const fs = require("node:fs");
const os = require("node:os");
const path = require("node:path");
const vm = require("node:vm");

const ROOT = path.resolve(__dirname, "..", "..");
const BINARY = process.env.CAUSTIC_BINARY;
assert.ok(BINARY, "CAUSTIC_BINARY names the caustic program");

// The job compiler's world, as Flamenco's documentation describes it.
function loadJobType() {
    const author = {
        Task: (name, type) => ({
            name, type, commands: [], dependencies: [],
            addCommand(command) { this.commands.push(command); },
            addDependency(task) { this.dependencies.push(task); },
        }),
        Command: (name, parameters) => ({ name, parameters }),
    };
    const context = vm.createContext({ author, path: path.posix, print: () => {} });
    const source = fs.readFileSync(path.join(ROOT, "farm", "flamenco", "caustic.js"), "utf8");
    return vm.runInContext(source + "\n;({ JOB_TYPE, compileJob })", context);
}

function compile(settings) {
    const { compileJob } = loadJobType();
    const tasks = [];
    compileJob({ settings, addTask: task => tasks.push(task) });
    return tasks;
}

const baseSettings = (output, overrides) => Object.assign({
    frames: "1-2", passes: 8, pass_chunk: 4, frame_chunk: 1, seed: 1, caustic: BINARY,
    caustic_flags: "--resolution 32x24 --photons 500", blendfile: "/farm/shot.blend", render_output_path: output,
}, overrides);

function checkJobType() {
    const { JOB_TYPE } = loadJobType();
    assert.equal(typeof JOB_TYPE.label, "string");
    const types = new Set(["string", "int32", "float", "bool"]);
    for (const setting of JOB_TYPE.settings) {
        assert.ok(types.has(setting.type), `setting ${setting.key}: type ${setting.type}`);
        if ("default" in setting) {
            const expected = { string: "string", int32: "number", float: "number", bool: "boolean" }[setting.type];
            assert.equal(typeof setting.default, expected, `setting ${setting.key}: default`);
        }
    }
    const keys = JOB_TYPE.settings.map(s => s.key);
    for (const key of ["frames", "passes", "pass_chunk", "frame_chunk", "blendfile", "render_output_path"]) {
        assert.ok(keys.includes(key), `setting ${key}`);
    }
}

// Tasks, commands and dependencies for 2 frames x 2 pass chunks, and for frames rendered together.
function checkTaskGraph() {
    const tasks = compile(baseSettings("/farm/out", {}));
    const [exportTask, ...rest] = tasks;
    assert.equal(exportTask.type, "blender");
    assert.equal(exportTask.commands[0].name, "blender-render");
    assert.match(exportTask.commands[0].parameters.args.join(" "), /caustic\.export_scene\(filepath="\/farm\/out\/scene\/scene\.gltf"\)/);
    const renders = rest.filter(t => t.name.startsWith("render-"));
    const merges = rest.filter(t => t.name.startsWith("merge-"));
    assert.equal(renders.length, 4);
    assert.equal(merges.length, 2);
    for (const render of renders) {
        assert.deepEqual(render.dependencies, [exportTask]);
        assert.equal(render.commands[0].name, "exec");
    }
    for (const [frame, merge] of [[1, merges[0]], [2, merges[1]]]) {
        const mine = renders.filter(r => r.commands[0].parameters.args[3] === `${frame}`);
        assert.deepEqual(merge.dependencies, mine, `merge of frame ${frame} waits for its renders`);
        const ranges = mine.map(r => r.commands[0].parameters.args[5]);
        assert.deepEqual(ranges, ["0..4", "4..8"]);
    }
    const together = compile(baseSettings("/farm/out", { frames: "1-3", frame_chunk: 2, passes: 10, pass_chunk: 4 }));
    const togetherRenders = together.filter(t => t.name.startsWith("render-"));
    assert.deepEqual(togetherRenders.map(t => t.commands[0].parameters.args.slice(3, 6).join(" ")),
        ["1,2 --pass-range 0..4", "1,2 --pass-range 4..8", "1,2 --pass-range 8..10",
         "3 --pass-range 0..4", "3 --pass-range 4..8", "3 --pass-range 8..10"]);
    const mergeOfTwo = together.find(t => t.name === "merge-2");
    assert.equal(mergeOfTwo.dependencies.length, 3);
    assert.throws(() => compile(baseSettings("/farm/out", { passes: 0 })), /passes/);
    assert.throws(() => compile(baseSettings("/farm/out", { frames: "5-2" })), /ends before it starts/);
}

// Runs the job's tasks in dependency order with the real renderer.
function runJob() {
    const output = fs.mkdtempSync(path.join(os.tmpdir(), "caustic-flamenco-"));
    const tasks = compile(baseSettings(output, {}));
    // What the export task would write.
    fs.mkdirSync(path.join(output, "scene"));
    fs.copyFileSync(path.join(ROOT, "scenes", "shot.gltf"), path.join(output, "scene", "scene.gltf"));
    fs.copyFileSync(path.join(ROOT, "scenes", "shot.bin"), path.join(output, "scene", "shot.bin"));
    const done = new Set();
    while (done.size < tasks.length) {
        const ready = tasks.find(t => !done.has(t) && t.dependencies.every(d => done.has(d)));
        assert.ok(ready, "a task waits for something that never runs");
        for (const command of ready.commands.filter(c => c.name === "exec")) {
            childProcess.execFileSync(command.parameters.exe, command.parameters.args, { stdio: "pipe" });
        }
        done.add(ready);
    }
    const whole = path.join(output, "whole");
    childProcess.execFileSync(BINARY, ["render", path.join(output, "scene", "scene.gltf"), "--frames", "1,2",
        "--passes", "8", "--seed", "1", "--progress", "none", "--no-reuse", "--resolution", "32x24", "--photons", "500",
        "-o", whole], { stdio: "pipe" });
    for (const frame of ["frame_0001.exr", "frame_0002.exr"]) {
        const merged = fs.readFileSync(path.join(output, frame));
        assert.ok(merged.equals(fs.readFileSync(path.join(whole, frame))), `${frame}: merged differs from the whole render`);
    }
    fs.rmSync(output, { recursive: true });
}

checkJobType();
checkTaskGraph();
runJob();
console.log("flamenco job type: settings, task graph and a local run of its tasks: ok");
