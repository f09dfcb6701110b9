"""The Analyse operator: run the headless job over the target meshes and write the result back.

In the UI the job (a generator of progress steps, `style_coanalysis.blender.job.run_steps`) is
stepped by TIMER events, so Blender stays responsive, shows progress, and Esc cancels. In background
mode timers never fire, so `execute` runs the generator to its end. Either way the scene is written
only once, at the end: a cancelled or failed run leaves it as it was, and a finished run is a single
undo step. Objects are kept by name between steps, never as `bpy_struct`s.
"""
import time
import traceback

import bpy

from ..style_coanalysis.blender import properties, space_store, writeback
from ..style_coanalysis.meshes import InputError
from ..style_coanalysis.options import (PAPER_ONLY, PARAMETERS, build_options, check_coordinates,
                                        check_shapes)
from ..style_coanalysis.progress import Cancelled

STEP_BUDGET_S = 0.1     # time spent in the generator per TIMER event before yielding to the UI


class Stepper:
    """Advances the job generator for a time budget per call (one call per TIMER event).

    Plain Python so its behaviour (progress, result, cancel) is testable without a window.
    `advance` returns True while the job runs; afterwards `result` holds the JobResult. Errors
    from the job propagate. `cancel` closes the generator, so the job's own clean-up runs.
    """

    def __init__(self, gen, budget_s: float = STEP_BUDGET_S, clock=time.monotonic):
        self.gen, self.budget_s, self.clock = gen, budget_s, clock
        self.progress = ("starting", 0, 1)
        self.result = None

    def advance(self) -> bool:
        deadline = self.clock() + self.budget_s
        try:
            while True:
                self.progress = next(self.gen)
                if self.clock() >= deadline:
                    return True
        except StopIteration as stop:
            self.result, self.gen = stop.value, None
            return False
        except BaseException:
            self.gen = None
            raise

    def run_to_end(self):
        self.budget_s = float("inf")
        self.advance()
        return self.result

    def cancel(self):
        gen, self.gen = self.gen, None
        if gen is not None:
            gen.close()

    def status(self) -> str:
        stage, done, total = self.progress[:3]
        detail = self.progress[3] if len(self.progress) > 3 and self.progress[3] else ""
        more = f", {detail}" if detail else ""
        return f"Style analysis: {stage} {done}/{total}{more} (Esc to cancel)"

    def fraction(self) -> float:
        _, done, total = self.progress[:3]
        return min(1.0, done / total) if total else 0.0


def target_names(context) -> list:
    """Names of the mesh objects to analyse (selected, or a collection's), sorted for determinism."""
    settings = context.scene.style_coanalysis
    if settings.target == "COLLECTION":
        col = settings.target_collection
        if col is None:
            return []
        in_scene = context.scene.objects
        objs = [o for o in col.all_objects if o.type == "MESH" and o.name in in_scene]
    else:
        objs = [o for o in context.selected_objects if o.type == "MESH"]
    return sorted(o.name for o in objs)


def _renderer(context) -> str:
    settings = context.scene.style_coanalysis
    if settings.renderer != "PREFERENCES":
        return settings.renderer
    prefs = properties.preferences(context)
    return prefs.renderer if prefs else "freestyle"


def _jobs(context) -> int:
    prefs = properties.preferences(context)
    return prefs.jobs if prefs else 1


def build_job(context):
    """(meshes, options, warnings, job module) for the current settings. Raises InputError naming the problem
    when fewer than two shapes can be analysed. Reads the scene, changes nothing."""
    from ..style_coanalysis.blender import job, scene as bscene  # heavy: only when running

    settings = context.scene.style_coanalysis
    names = target_names(context)
    depsgraph = context.evaluated_depsgraph_get()
    meshes, warnings = [], []
    for name in names:
        obj = context.scene.objects[name]
        try:
            mesh = bscene.mesh_from_object(obj, depsgraph)
        except (InputError, ValueError) as exc:
            warnings.append(f"'{name}' skipped: {exc}")
            continue
        if len(mesh.vertices) != len(obj.data.vertices):
            # The weights must line up with the object's own vertices to be written back.
            warnings.append(f"'{name}' skipped: its modifiers change the vertex count "
                            "(apply them first)")
            continue
        meshes.append(mesh)
    if len(meshes) < 2:
        detail = f" ({'; '.join(warnings)})" if warnings else ""
        raise InputError(f"Need at least two mesh objects to analyse, got {len(meshes)}{detail}")

    kept = {m.name for m in meshes}
    known = set(settings.label_names())
    labels = {}
    for name in sorted(kept):
        label = context.scene.objects[name].style_coanalysis.label
        if label and label in known:
            labels[name] = label
    triplets = []
    for i, t in enumerate(settings.triplets):
        abc = t.names()
        if abc is None:
            warnings.append(f"Triplet {i + 1} ignored: one of its objects was deleted")
        elif not set(abc) <= kept:
            warnings.append(f"Triplet {i + 1} ignored: {', '.join(abc)} are not all analysed")
        else:
            triplets.append(abc)

    # the same builder and checks as the command line (style_coanalysis/options.py)
    options = build_options(
        renderer=_renderer(context), up=settings.up, jobs=_jobs(context),
        cache_dir=properties.cache_dir(context), seed=settings.seed,
        clusters="auto" if settings.auto_clusters else settings.n_clusters,
        method=settings.method, labels=labels or None, triplets=triplets or None,
        **{option: getattr(settings, properties.PARAMETER_PROPS[option])
           for option in PARAMETERS if settings.method == "paper" or option not in PAPER_ONLY})
    for m in meshes:
        check_coordinates(m)
    check_shapes(options, [m.name for m in meshes])
    return meshes, options, warnings, job


class STYLE_OT_analyse(bpy.types.Operator):
    """Cluster the target meshes by decorative style and mark their style regions"""

    bl_idname = "style.analyse"
    bl_label = "Analyse Style"
    bl_options = {"REGISTER", "UNDO"}

    _running = False    # one analysis at a time (class-wide: there is one window manager)

    @classmethod
    def poll(cls, context):
        if cls._running:
            cls.poll_message_set("An analysis is already running (Esc cancels it)")
            return False
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode to analyse")
            return False
        settings = context.scene.style_coanalysis
        if settings.target == "COLLECTION" and settings.target_collection is None:
            cls.poll_message_set("Choose the collection to analyse")
            return False
        if len(target_names(context)) < 2:
            where = ("in the collection" if settings.target == "COLLECTION" else "selected")
            cls.poll_message_set(f"Need at least two mesh objects {where}")
            return False
        return True

    # -- shared start / finish

    def _start(self, context):
        try:
            meshes, options, warnings, job = build_job(context)
        except InputError as exc:
            self.report({"ERROR"}, str(exc))
            return False
        for w in warnings:
            self.report({"WARNING"}, w)
        self._stepper = Stepper(job.run_steps(meshes, options))
        return True

    def _fail(self, exc):
        if isinstance(exc, Cancelled):
            self.report({"WARNING"}, "Style analysis cancelled: the scene is unchanged")
        elif isinstance(exc, InputError):
            self.report({"ERROR"}, str(exc))
        else:
            traceback.print_exc()
            self.report({"ERROR"}, f"Analysis failed: {type(exc).__name__}: {exc}")

    def _finish(self, context, result):
        try:
            summary = writeback.write_results(context.scene, result)
            space_store.write_scene(context.scene, result.style_space)   # for operators/uses.py
        except writeback.WritebackError as exc:
            self.report({"ERROR"}, f"Results not written: {exc}")
            return {"CANCELLED"}
        for name, reason in result.skipped:
            self.report({"WARNING"}, f"'{name}' skipped: {reason}")
        if summary["shared_meshes"]:
            self.report({"INFO"}, "Meshes shared by several objects got their mean weights: "
                        + ", ".join(summary["shared_meshes"]))
        self.report({"INFO"}, f"{summary['objects']} shapes in {summary['clusters']} style "
                              "clusters")
        from ..style_coanalysis.report import run_notes   # PIL: only once a run ends
        for level, note in run_notes(result.report):
            self.report({level}, note)
        return {"FINISHED"}

    # -- background / redo: synchronous

    def execute(self, context):
        if not self._start(context):
            return {"CANCELLED"}
        try:
            result = self._stepper.run_to_end()
        except Exception as exc:  # noqa: BLE001 - reported to the person, scene untouched
            self._fail(exc)
            return {"CANCELLED"}
        finally:
            self._stepper = None
        return self._finish(context, result)

    # -- interactive: stepped by timer events

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        if not self._start(context):
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.05, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 1000)
        type(self)._running = True
        context.workspace.status_text_set("Style analysis starting (Esc to cancel)")
        return {"RUNNING_MODAL"}

    def _cleanup(self, context):
        wm = context.window_manager
        if getattr(self, "_timer", None) is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        stepper, self._stepper = getattr(self, "_stepper", None), None
        if stepper is not None:
            stepper.cancel()    # lets the job release its workers and threads
        type(self)._running = False

    def modal(self, context, event):
        if event.type == "ESC":
            self._cleanup(context)
            self.report({"WARNING"}, "Style analysis cancelled: the scene is unchanged")
            return {"CANCELLED"}
        if event.type != "TIMER":
            if event.type in {"MIDDLEMOUSE", "WHEELUPMOUSE", "WHEELDOWNMOUSE", "TRACKPADPAN",
                              "TRACKPADZOOM", "MOUSEMOVE"}:
                return {"PASS_THROUGH"}     # let the view be navigated while it runs
            return {"RUNNING_MODAL"}        # but no edits: the result must still fit the scene
        stepper = self._stepper
        try:
            running = stepper.advance()
        except Exception as exc:  # noqa: BLE001 - reported to the person, scene untouched
            self._cleanup(context)
            self._fail(exc)
            return {"CANCELLED"}
        if running:
            context.window_manager.progress_update(int(1000 * stepper.fraction()))
            context.workspace.status_text_set(stepper.status())
            return {"RUNNING_MODAL"}
        self._cleanup(context)
        return self._finish(context, stepper.result)

    def cancel(self, context):
        """Blender aborts the modal (file load, window closed): stop without writing."""
        self._cleanup(context)


CLASSES = (STYLE_OT_analyse,)
