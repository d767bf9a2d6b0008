"""Background work: the worker process, the runner that drives it, the controller the window uses.

May import ``ursim_gui.views`` (error boxes) and ``ursim_gui.model`` (the job values).

- :mod:`~ursim_gui.jobs.process`: :class:`JobProcess`, a spawned child that runs the core jobs.
- :mod:`~ursim_gui.jobs.runner`: :class:`JobRunner`, Qt signals over one job at a time.
- :mod:`~ursim_gui.jobs.controller`: :class:`JobController`, queues segment/match jobs and applies results.
"""
