"""The methods: what each one's networks score and see, and the rule that picks its primitive.

Networks, agent, export and the command lines read this table, so a new method is one `register`
call (plus its test), and a new rule one `Rule`: the agent asks the rule, never its name.
Primitives are `sim.primitives.PUSH` (0) and `GRASP` (1); views index the cameras
(`Observation`'s V axis).
"""
from __future__ import annotations

import dataclasses
from typing import Callable

import jax.numpy as jnp

from mvcoba_jax.sim.config import CameraConfig, SceneConfig
from mvcoba_jax.sim.primitives import GRASP, PUSH

@dataclasses.dataclass(frozen=True)
class Rule:
  """How a method picks its primitive, and what follows from it: its Q-learning target's max and
  its exploration. `name` and `text` describe it in model.json; the export traces `pick` into
  the ONNX graph."""
  name: str
  text: str  # the rule in words (model.json)
  pick: Callable  # (changed (B,) bool, best (B, 2) each primitive's max) -> (B,) int32 primitive
  # `pick` is traced into the export's graph: jax2onnx cannot trace jnp's jitted helpers
  # take_along_axis, unravel_index and integer `//` (use lax.div), and the export says so.
  future_over_both: bool  # the target's max is over both primitives' maps, else the one at s'
  explores_primitive: bool  # a random action draws its primitive too, else keeps the rule's
  compares_primitives: bool  # `pick` reads the maps' maxima, else the primitive is given


# MV-COBA's change observation: `changed` is True also before the first action of an episode.
CHANGE = Rule('change', 'grasp if the previous action changed the scene (also before the first '
              'action of an episode), else push',
              lambda changed, best: jnp.where(changed, GRASP, PUSH).astype(jnp.int32),
              future_over_both=False, explores_primitive=False, compares_primitives=False)
MAX_Q = Rule('max_q', 'the primitive whose Q map holds the larger maximum (ties: push)',
             lambda changed, best: jnp.argmax(best, axis=-1).astype(jnp.int32),
             future_over_both=True, explores_primitive=True, compares_primitives=True)
ALWAYS_GRASP = Rule('grasp', 'always grasp',
                    lambda changed, best: jnp.full(changed.shape, GRASP, jnp.int32),
                    future_over_both=False, explores_primitive=False,
                    compares_primitives=False)
RULES = {rule.name: rule for rule in (CHANGE, MAX_Q, ALWAYS_GRASP)}


@dataclasses.dataclass(frozen=True)
class Fcn:
  """One fully convolutional network of a method: the primitives it scores, the camera views
  it reads."""
  primitives: tuple[int, ...]
  views: tuple[int, ...]


@dataclasses.dataclass(frozen=True)
class Method:
  name: str
  fcns: tuple[Fcn, ...]
  rule: Rule
  # Its networks read one heightmap fused from their views, the highest point per cell (MVP's
  # fusion of viewpoints), instead of one stream pair per view.
  fuse: bool = False
  # The rule compares Q maps weighted by CPG's suppression of actions that cannot act
  # (`suppression.py`): grasps whose fingers land on something, pushes with nothing ahead.
  suppress: bool = False
  # Camera poses the method needs (a camera it moves); choosing it sets scene.cameras to them.
  cameras: tuple[CameraConfig, ...] = ()

  def __post_init__(self):
    if not isinstance(self.rule, Rule):
      raise ValueError(f'method {self.name!r}: its rule must be a methods.Rule (for example one '
                       f'of {", ".join(RULES)}), got {self.rule!r}')
    scored = [p for fcn in self.fcns for p in fcn.primitives]
    if not scored or len(scored) != len(set(scored)) or not set(scored) <= {PUSH, GRASP}:
      raise ValueError(f'method {self.name!r}: its networks must score each primitive at most '
                       f'once, got {scored}')

    if self.cameras and max(self.views) >= len(self.cameras):
      raise ValueError(f'method {self.name!r} reads views {self.views} of {len(self.cameras)} '
                       'cameras')

  @property
  def views(self) -> tuple[int, ...]:
    """Camera views its networks read, in order."""
    return tuple(sorted({v for fcn in self.fcns for v in fcn.views}))


_REGISTRY: dict[str, Method] = {}


def register(method: Method) -> Method:
  _REGISTRY[method.name] = method
  return method


def unregister(name: str) -> None:
  del _REGISTRY[name]


def names() -> tuple[str, ...]:
  return tuple(_REGISTRY)


def get(name: str) -> Method:
  if name not in _REGISTRY:
    raise ValueError(f'unknown network method {name!r}; allowed: {", ".join(_REGISTRY)}')
  return _REGISTRY[name]


register(Method('mvcoba', fcns=(Fcn((PUSH, GRASP), (0, 1)),), rule=CHANGE))
register(Method('mvcoba_2fcn', fcns=(Fcn((PUSH,), (0,)), Fcn((GRASP,), (1,))), rule=CHANGE))
register(Method('vpg', fcns=(Fcn((PUSH,), (0,)), Fcn((GRASP,), (0,))), rule=MAX_Q))
register(Method('grasp_only', fcns=(Fcn((GRASP,), (0,)),), rule=ALWAYS_GRASP))
# MVP-like (Morrison et al. 2019): grasp only, one camera that looks from every one of its four
# poses before each grasp (the two fixed cameras' and two across the other axis), fused.
register(Method('mvp', fcns=(Fcn((GRASP,), (0, 1, 2, 3)),), rule=ALWAYS_GRASP, fuse=True,
                cameras=SceneConfig().cameras + (CameraConfig(pos=(0.0, 0.35, 0.65)),
                                                 CameraConfig(pos=(0.0, -0.35, 0.65)))))
# CPG (Collaborative Pushing-Grasping): VPG's two FCNs and max-Q, over suppressed Q maps.
register(Method('cpg', fcns=(Fcn((PUSH,), (0,)), Fcn((GRASP,), (0,))), rule=MAX_Q, suppress=True))
