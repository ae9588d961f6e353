"""A `spall run` in the background: its progress read from the progress bar it draws on stderr,
stopped with Ctrl-C's signal (the run finishes its step, keeps every frame written and a
checkpoint, and exits 130)."""
import re
import signal
import subprocess
import threading

_PROGRESS = re.compile(r"frame (\d+)/(\d+).*?t=([0-9.eE+-]+) s")


class SpallJob:
    def __init__(self, command, duration_s):
        self.command = list(command)
        self.duration_s = duration_s
        self.fraction = 0.0
        self.fractions = []  # every progress the run reported, in order
        self.status = ""
        self.messages = []  # what spall said besides its progress bar (notes, errors)
        self.cancelled = False
        self._lock = threading.Lock()
        self._process = subprocess.Popen(self.command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self._readers = [threading.Thread(target=self._read, args=(stream,), daemon=True)
                         for stream in (self._process.stdout, self._process.stderr)]
        for reader in self._readers:
            reader.start()

    def _read(self, stream):
        # The progress bar rewrites its line with '\r': split on both.
        pending = b""
        while True:
            chunk = stream.read1(4096) if hasattr(stream, "read1") else stream.read(4096)
            if not chunk:
                break
            pending += chunk
            *lines, pending = re.split(rb"[\r\n]", pending)
            for line in lines:
                self._take(line.decode(errors="replace").strip())
        self._take(pending.decode(errors="replace").strip())

    def _take(self, line):
        if not line:
            return
        match = _PROGRESS.search(line)
        with self._lock:
            if match:
                self.status = f"frame {match.group(1)}/{match.group(2)}"
                if self.duration_s > 0:
                    self.fraction = max(self.fraction, min(1.0, float(match.group(3)) / self.duration_s))
                    self.fractions.append(self.fraction)
            elif not line.startswith("["):
                self.messages.append(line)

    def poll(self):
        """None while it runs, else its exit code (0: done; 130: stopped on request)."""
        code = self._process.poll()
        if code is not None:
            for reader in self._readers:
                reader.join()
            if code == 0:
                self.fraction = 1.0
        return code

    def cancel(self):
        """Asks spall to stop as Ctrl-C would."""
        if self._process.poll() is None:
            self.cancelled = True
            self._process.send_signal(signal.SIGINT)

    def wait(self, timeout_s=None):
        return self._process.wait(timeout_s)

    def error(self):
        with self._lock:
            said = [m for m in self.messages if "error" in m.lower() or m.startswith("spall")]
        return said[-1] if said else f"spall exited with {self._process.returncode}"
