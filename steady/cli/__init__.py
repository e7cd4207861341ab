"""The command lines of :mod:`steady`, the top floor: nothing in the library imports them.

- :mod:`steady.cli.solve` -- ``runin-steady`` (``python -m steady``): the
  steady face of a scene file;
- :mod:`steady.cli.fit` -- ``runin-fit`` (``python -m steady.cli.fit``):
  wear ratios from a measured face;
- :mod:`steady.cli.design` -- ``runin-design`` (``python -m
  steady.cli.design``): the design rule;
- :mod:`steady.cli.examples` -- ``runin-examples`` (``python -m
  steady.cli.examples``): the shipped example scenes, listed and copied;
- :mod:`steady.cli.common` -- what every command shares (exit statuses,
  one-line errors, output checks, ``--memory-limit``), also for
  ``runin-transient``;
- :mod:`steady.cli.entry` -- the entry points of the commands, which handle
  Ctrl-C before the heavy modules load.
"""
