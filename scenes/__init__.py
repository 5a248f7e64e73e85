"""Declarative YAML of spectwin's rigs (``rigs/``), cameras (``cameras/``), ground-truth
materials (``materials/``) and design sweeps (``sweeps/``, ``spectwin sweep``).

The files ship inside the installed package and are read through :mod:`importlib.resources`
(:func:`twin.rigs.yaml_config.scene_folder`); a user's own YAML file is given to the commands by
path.
"""
