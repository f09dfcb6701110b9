"""A drawing worker that dies like a crashed Blender, for tests/test_guarantees.py.

Spawned worker processes import it by name (the test folder is on the sys.path they inherit).
Shapes named 'crash*' kill their worker every time; shapes named 'once*' kill it the first time
only (a marker file under $SCA_CRASH_MARKERS remembers); every other shape is drawn for real.
"""
import os

from style_coanalysis.blender.batch import _worker_draw


def crashing_draw(name, vertices, faces, settings, threads):
    if name.startswith("crash"):
        os._exit(3)
    if name.startswith("once"):
        marker = os.path.join(os.environ["SCA_CRASH_MARKERS"], name)
        if not os.path.exists(marker):
            open(marker, "w").close()
            os._exit(3)
    return _worker_draw(name, vertices, faces, settings, threads)
