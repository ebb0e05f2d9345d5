"""Gripper presets (`scene.gripper=NAME`), each number with its source.

The simulated gripper is a palm and two box fingers on slide joints (`scene.build_mjcf`): what a
preset sets is what a policy's grasps depend on, the fingers' size, how far they open, how hard
they squeeze and how they grip. Linkages (the 2F-85's) and finger pads' shapes are left out.
A user's own gripper is a preset file's `scene.gripper` or `--set scene.gripper.FIELD=VALUE`.
"""
from __future__ import annotations

from mvcoba_jax.sim.config import ConfigError, GripperConfig

# The RG2-like gripper of every landed figure (OnRobot RG2 datasheet: 110 mm stroke, 3-40 N;
# fingers and palm as the project modelled them: 2 x 1 x 6 cm fingers).
RG2 = GripperConfig()

# Robotiq 2F-85: 85 mm stroke, 20-235 N grip force (Robotiq's 2F-85/2F-140 instruction manual,
# section 6.1); pads 22 mm wide and 8 mm thick (MuJoCo Menagerie's robotiq_2f85, `pad_box1` and
# `pad_box2`); the fingers' reach below the base, about 5.5 cm, is our estimate from that model's
# linkage, and so is the base's size; each finger's drive is held to 30 N (the low end of the
# range: the simulation squeezes, it does not crush); pad friction 1.0.
ROBOTIQ_2F85 = GripperConfig(
    name='robotiq_2f85', finger_width=0.022, finger_thickness=0.008, finger_length=0.055,
    max_opening=0.085, palm=(0.075, 0.075, 0.02), finger_force=30.0, finger_friction=1.0)

# Franka Hand: 80 mm stroke (2 x 40 mm) and 70 N continuous grip force (Franka's datasheet),
# 35 N a finger here; fingertips 22 mm wide and 15 mm thick, reaching 5.3 cm below the hand
# (Menagerie's franka_emika_panda `fingertip_pad_collision_*` boxes: +-11 mm, +-7.5 mm, up to
# z 0.0535); the hand taken as a 8 x 20 x 3 cm box (our estimate from Menagerie's hand capsule,
# 4 cm in radius); friction 1.0 (Menagerie's pads).
FRANKA_HAND = GripperConfig(
    name='franka_hand', finger_width=0.022, finger_thickness=0.015, finger_length=0.053,
    max_opening=0.08, palm=(0.08, 0.2, 0.03), finger_force=35.0, finger_friction=1.0)

PRESETS = {g.name: g for g in (RG2, ROBOTIQ_2F85, FRANKA_HAND)}


def preset(name: str) -> GripperConfig:
  """The gripper preset of that name; ConfigError naming the known ones otherwise."""
  if name not in PRESETS:
    raise ConfigError(f'scene.gripper={name!r}: unknown gripper; presets: {", ".join(PRESETS)} '
                      '(or set its fields: scene.gripper.max_opening=...)')
  return PRESETS[name]
