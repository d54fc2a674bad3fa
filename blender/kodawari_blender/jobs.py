"""The operators' work in chunks, shared by scripts and the UI (issue 33: progress in the
status bar, Esc cancels, nothing half-made).

An operation is a generator that does one chunk of work (frames simulated, armatures
built, frames keyed) between two yields of (fraction done, what it is doing), and returns
its result. A Job runs it:

- execute() (EXEC_DEFAULT, scripts) calls Job.run(): every chunk, at once;
- invoke() (the UI) starts the same Job under a window-manager timer; each tick runs
  chunks for about a tenth of a second (Job.run(budget)), then hands the window back so
  that it redraws the progress and sees Esc; Esc and right-click call Job.cancel();
- an error from any chunk calls Job.cancel() as well.

Job.cancel() closes the generator (its `finally` blocks run), removes every data-block
made since the job started (objects, armatures, meshes, actions, materials, ...), runs
the undo functions the operation registered for what it changed on the user's own data
(rotation modes, a created animation_data, an NLA track), puts back the selection, the
active object and the current frame, and removes the job's temporary folder: the file is
as it was before the call. A finished job puts back the selection and the frame too.
"""
import os
import shutil
import tempfile
import time

import bpy

# The data-block collections a job may add to (the glTF importer makes objects,
# armatures, meshes, actions, materials, images, textures, node groups; the flock a
# collection; a baked file may hold cameras and lights).
KINDS = ("objects", "armatures", "meshes", "actions", "materials", "collections", "images", "textures",
         "node_groups", "cameras", "lights", "curves")


def snapshot():
    """The pointers of every data-block of KINDS now."""
    return {name: {b.as_pointer() for b in getattr(bpy.data, name)} for name in KINDS}


def remove_new(before):
    """Removes every data-block made since `before` (objects first: they use the rest)."""
    for name in KINDS:
        data = getattr(bpy.data, name)
        for block in [b for b in data if b.as_pointer() not in before[name]]:
            data.remove(block)


def remove_unused_new(before):
    """Removes the data-blocks made since `before` that nothing uses any more (what an
    import leaves once its objects are removed: their meshes, armatures, actions and
    materials), in KINDS' order, users first, so that each removal frees the next."""
    for name in KINDS:
        data = getattr(bpy.data, name)
        for block in [b for b in data if b.as_pointer() not in before[name] and b.users == 0]:
            data.remove(block)


class Job:
    """One operation in chunks. `operation(job)` makes the generator; it may put files in
    job.folder (removed at the end) and register undo functions with job.on_cancel()."""

    def __init__(self, context, title, operation):
        self.title = title
        self.scene = context.scene
        self.view_layer = context.view_layer
        self.before = snapshot()
        self.selected = [o.name for o in context.selected_objects]
        self.active = context.view_layer.objects.active.name if context.view_layer.objects.active else None
        self.frame = context.scene.frame_current
        self.folder = tempfile.mkdtemp(prefix="kodawari-")
        self.undo = []
        self.fraction, self.doing = 0.0, "starting"
        self.chunks = 0
        self.result = None
        self.done = self.cancelled = False
        self.started = time.perf_counter()
        self.steps = operation(self)

    def on_cancel(self, function):
        """Registers `function` to undo a change to the user's data if the job is cancelled
        (run in reverse order of registration)."""
        self.undo.append(function)

    def step(self):
        """Runs one chunk; False once the operation has returned (self.result). An error
        raised by the chunk cancels the job and propagates."""
        if self.done:
            return False
        try:
            self.fraction, self.doing = next(self.steps)
            self.chunks += 1
            return True
        except StopIteration as stop:
            self.result = stop.value
            self.done = True
            self._restore_view()
            self._remove_folder()
            return False
        except BaseException:
            self.cancel()
            raise

    def run(self, budget=None):
        """Runs chunks until the end, or until `budget` seconds have passed; False once done."""
        start = time.perf_counter()
        while self.step():
            if budget is not None and time.perf_counter() - start >= budget:
                return True
        return False

    def cancel(self):
        """Undoes everything the job did so far (see the module's docstring)."""
        if self.done:
            return
        self.done = self.cancelled = True
        try:
            self.steps.close()
        finally:
            remove_new(self.before)
            for function in reversed(self.undo):
                function()
            self._restore_view()
            self._remove_folder()

    def status(self):
        return f"{self.title}: {self.doing} ({100 * self.fraction:.0f}%), Esc to cancel"

    def _restore_view(self):
        self.view_layer.update()  # objects removed by the job leave the layer's list here
        objects = self.view_layer.objects
        for obj in list(objects):
            if obj is not None and obj.select_get():
                obj.select_set(False)
        for name in self.selected:
            obj = objects.get(name)
            if obj is not None:
                obj.select_set(True)
        objects.active = objects.get(self.active) if self.active else None
        self.scene.frame_set(self.frame)

    def _remove_folder(self):
        if self.folder and os.path.isdir(self.folder):
            shutil.rmtree(self.folder, ignore_errors=True)


class ModalJob:
    """The UI half of an operator whose work is a Job: a mixin for bpy.types.Operator
    subclasses that define start(context) -> Job or None (None: refused, reported) and
    finish(context, job) -> {'FINISHED'} (reports the result); execute() and invoke() come
    from here. ERRORS: the exceptions whose message is the operation's error; any other is
    reported with its type (describe()), never left as a traceback."""

    ERRORS = (RuntimeError, OSError)
    TICK = 0.1  # seconds of work per timer tick: the window stays responsive to Esc

    def execute(self, context):
        job = self.start(context)
        if job is None:
            return {'CANCELLED'}
        try:
            job.run()
        except Exception as error:  # the job cancelled itself (Job.step): report, never a traceback
            self.report({'ERROR'}, f"{job.title}: {self.describe(error)}")
            return {'CANCELLED'}
        return self.finish(context, job)

    def describe(self, error):
        """An error's report: ERRORS say what went wrong themselves; anything else is named
        with its type (a MemoryError, or a bug of the add-on's, reported rather than left
        as a traceback with the progress bar and the timer running)."""
        if isinstance(error, self.ERRORS):
            return str(error)
        if isinstance(error, MemoryError):
            return "out of memory; make fewer birds, chains or frames (nothing was made)"
        return f"{type(error).__name__}: {error} (nothing was made; please report this)"

    def invoke(self, context, event):
        if context.window is None:  # no window to tick in (a background script's INVOKE)
            return self.execute(context)
        job = self.start(context)
        if job is None:
            return {'CANCELLED'}
        self._job = job
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0.0, 1.0)
        self._show(context)
        return {'RUNNING_MODAL'}

    def modal(self, context, event):
        job = self._job
        if event.type in {'ESC', 'RIGHTMOUSE'} and event.value == 'PRESS':
            self._end(context)
            job.cancel()
            self.report({'WARNING'}, f"{job.title}: cancelled, nothing made")
            return {'CANCELLED'}
        if event.type != 'TIMER':
            # Everything else waits: the scene must not change under the job.
            return {'RUNNING_MODAL'}
        try:
            going = job.run(self.TICK)
        except Exception as error:  # as execute(): the timer and status bar end too
            self._end(context)
            self.report({'ERROR'}, f"{job.title}: {self.describe(error)}")
            return {'CANCELLED'}
        if going:
            self._show(context)
            return {'RUNNING_MODAL'}
        self._end(context)
        return self.finish(context, job)

    def cancel(self, context):
        # Blender ends the modal operator (its window closes, the file is reloaded).
        self._end(context)
        self._job.cancel()

    def _show(self, context):
        context.window_manager.progress_update(self._job.fraction)
        if context.workspace is not None:
            context.workspace.status_text_set(self._job.status())

    def _end(self, context):
        wm = context.window_manager
        if getattr(self, "_timer", None) is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
