"""The handlers of the ``demseis`` commands, one module per command group of :mod:`demseis.cli`.

A command's parser names its handler ``"group:function"``; :func:`demseis.cli.main` imports
the group's module here only when that command runs, so these modules import what they run at
the top and ``demseis --help`` imports none of them.
"""
