"""The MV-COBA authors' released code's learning recipe (their VPG fork's trainer.py, main.py and
robot.py) at the default preset's scale: a failed grasp earns 0 and a push that changes nothing
-1; an action that changed nothing has no future; the future is the max over both primitives'
maps; a grasp is labelled at its rotation and turned half way; each update trains on the fresh
transitions besides the replayed ones; training scenes are heaps dropped in random orientations.

Not copied: their zero-future test reads `not change_1 or not change_2 and not grasp_success`,
which by Python's precedence zeroes the future whenever camera 1 alone saw no change, whatever
camera 2 saw. Ours zeroes it when neither camera saw a change (`Outcome.changed`), so that the
target does not depend on which camera is called the first.
"""
import dataclasses

from mvcoba_jax.config import Config, EnvConfig, SceneConfig, TrainConfig


def get_config() -> Config:
  train = dataclasses.replace(TrainConfig(), failed_grasp_reward=0.0, no_change_push_reward=-1.0,
                              bootstrap_no_change=False, future_max='both', grasp_symmetry=True,
                              fresh_in_batch=True)
  # Heaps touch more objects at once than spread drops: MJX's contact caps as evaluation's.
  scene = SceneConfig()
  scene = dataclasses.replace(scene, max_contact_points=10 * scene.num_slots,
                              max_geom_pairs=2 * scene.num_slots)
  return Config(scene=scene, env=dataclasses.replace(EnvConfig(), drop='heap'), train=train)
