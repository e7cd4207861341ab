"""The command line of :mod:`transient`, the top floor: nothing in the library imports it.

- :mod:`transient.cli.runin` -- ``runin-transient`` (``python -m transient``):
  the run-in of a scene file, its checks, the summary;
- :mod:`transient.cli.run_file` -- the run file of the command: inputs,
  checkpoints, backup, resume and the settings history;
- :mod:`transient.cli.progress` -- the progress bar.

What every command shares (exit statuses, one-line errors, output checks,
``--memory-limit``) is :mod:`steady.cli.common`.
"""
