"""Long jobs (bake, simulate) as generators of progress in [0, 1]: run at once from a script, or
step by step from a modal operator showing Blender's progress and cancelled by Esc.

A job's generator must clean up in a finally clause: cancelling closes it (GeneratorExit)."""


def run(job, window_manager=None):
    """Runs the job to its end (a script, or blender -b)."""
    if window_manager is not None:
        window_manager.progress_begin(0.0, 1.0)
    try:
        for fraction in job:
            if window_manager is not None:
                window_manager.progress_update(fraction)
    finally:
        if window_manager is not None:
            window_manager.progress_end()


class ModalJob:
    """Mixin of an operator: make_job(context) returns the generator; invoke runs it modally."""
    _job = None
    _timer = None

    def invoke(self, context, event):
        try:
            self._job = self.make_job(context)
        except (RuntimeError, ValueError) as error:
            self.report({"ERROR"}, "%s: %s" % (self.bl_label, error))
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)
        self._timer = wm.event_timer_add(0.001, window=context.window)
        wm.modal_handler_add(self)
        context.workspace.status_text_set("%s: Esc cancels" % self.bl_label)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            self._job.close()
            self.report({"WARNING"}, "%s: cancelled, nothing written" % self.bl_label)
            return self._finish(context, {"CANCELLED"})
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        try:
            context.window_manager.progress_update(next(self._job))
        except StopIteration:
            self.report({"INFO"}, "%s: done" % self.bl_label)
            return self._finish(context, {"FINISHED"})
        except (RuntimeError, ValueError) as error:
            self.report({"ERROR"}, "%s: %s" % (self.bl_label, error))
            return self._finish(context, {"CANCELLED"})
        return {"RUNNING_MODAL"}

    def _finish(self, context, result):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        return result

    def execute(self, context):
        try:
            run(self.make_job(context), context.window_manager)
        except (RuntimeError, ValueError) as error:
            self.report({"ERROR"}, "%s: %s" % (self.bl_label, error))
            return {"CANCELLED"}
        return {"FINISHED"}

