"""One `caustic render` process: started with `--progress json`, read line by line on a thread,
ended on request (its whole process group, so nothing is left behind)."""

import json
import os
import queue
import signal
import subprocess
import threading


class RenderProcess:
    """A running `caustic render`; `events()` gives its JSON lines as they come."""

    def __init__(self, args):
        self.args = args
        self._events = queue.Queue()
        self._stderr = []
        self._warnings_seen = 0
        self.process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                        start_new_session=True)
        self._readers = [threading.Thread(target=self._read_stdout, daemon=True),
                         threading.Thread(target=self._read_stderr, daemon=True)]
        for reader in self._readers:
            reader.start()

    def _read_stdout(self):
        for line in self.process.stdout:
            try:
                self._events.put(json.loads(line))
            except json.JSONDecodeError:
                self._stderr.append(line.rstrip())

    def _read_stderr(self):
        for line in self.process.stderr:
            self._stderr.append(line.rstrip())

    @property
    def pid(self):
        return self.process.pid

    def events(self, timeout_s):
        """The lines that arrived, waiting up to `timeout_s` for the first."""
        found = []
        try:
            found.append(self._events.get(timeout=timeout_s))
            while True:
                found.append(self._events.get_nowait())
        except queue.Empty:
            return found

    def exit_code(self):
        """The exit code once the process has ended and its output is read, else None."""
        code = self.process.poll()
        if code is None or any(reader.is_alive() for reader in self._readers):
            return None
        return code

    def error_message(self):
        """The renderer's own message about why it failed."""
        errors = [line.removeprefix("caustic: error: ") for line in self._stderr if "error" in line]
        return (errors or self._stderr or [f"the renderer ended with exit code {self.process.returncode}"])[-1]

    def new_warnings(self):
        """The renderer's warnings since the last call."""
        warnings = [line for line in self._stderr if "warning" in line]
        fresh, self._warnings_seen = warnings[self._warnings_seen:], len(warnings)
        return fresh

    def _signal(self, number):
        try:
            if hasattr(os, "killpg"):
                os.killpg(self.process.pid, number)
            else:
                self.process.kill()
        except ProcessLookupError:
            pass

    def stop(self):
        """Ends the process and everything it started, and waits for it."""
        if self.process.poll() is None:
            self._signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._signal(getattr(signal, "SIGKILL", signal.SIGTERM))
        self.process.wait()
        for reader in self._readers:
            reader.join(timeout=5)
        self.process.stdout.close()
        self.process.stderr.close()
