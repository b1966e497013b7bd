"""A scene: one run of the platform as the user writes it (a TOML file), its keys declared in
schema.py, read and checked by reader.py into the `Scene` of model.py; its signals as the
trajectory FMU's parameters (signals.py), a drive FMU of the user's own (drive_fmu.py) and the
project's parameter sets (parameter_sets.py)."""

from .model import Pulse, Ramp, Scene, Signal, Sine, Step, signals_document
from .reader import load_scene, shipped, shipped_scenes
from .schema import SceneError

__all__ = ["Pulse", "Ramp", "Scene", "SceneError", "Signal", "Sine", "Step", "load_scene", "shipped", "shipped_scenes",
           "signals_document"]
