"""Scenes the Python tests share, as dicts for isochor.scene()."""

# A free bar of muscle on three symmetry planes (tests/test_muscle.cpp's bundle): CNH, statics in
# 6 increments, fibres along x activated from 0 to 0.8.
BUNDLE = {
    "mesh": {"shape": "box", "cells": [3, 2, 2], "size": [1.0, 0.5, 0.5], "center": [0.5, 0.25, 0.25]},
    "material": {"model": "cnh", "mu": 1000.0, "lambda": 5000.0},
    "zones": {"global": True},
    "forces": {"gravity": [0.0, 0.0, 0.0]},
    "boundary": [{"select": {"kind": "set", "name": f"{a}min"}, "components": [a]} for a in "xyz"],
    "integrator": {"kind": "static"},
    "frames": {"count": 6},
    "muscle": [{"name": "bundle", "select": {"kind": "all"}, "direction": [1.0, 0.0, 0.0], "sigma_max": 2000.0,
                "activation_keys": {"times": [0.0, 1.0], "values": [0.0, 0.8]}}],
}
