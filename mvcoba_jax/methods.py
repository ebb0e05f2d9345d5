"""The methods: what each one's networks score and see, and the rule that picks its primitive.

Networks, agent, export and the command lines read this table, so a new method is one `register`
call (plus its test). Primitives are `sim.primitives.PUSH` (0) and `GRASP` (1); views index the
cameras (`Observation`'s V axis).
"""
from __future__ import annotations

import dataclasses

from mvcoba_jax.sim.config import CameraConfig, SceneConfig
from mvcoba_jax.sim.primitives import GRASP, PUSH

# How a method picks its primitive, and how its Q-learning target and exploration follow:
# 'change' (MV-COBA's rule): grasp if the previous action changed the scene (also before the
#   first action of an episode), else push; the target's max is over the primitive the rule
#   would pick at the next state.
# 'max_q' (VPG): the primitive whose Q map holds the larger maximum (ties: push); the target's
#   max is over both; exploration draws the primitive too.
# 'grasp': always grasp.
RULES = {
    'change': 'grasp if the previous action changed the scene (also before the first action of '
              'an episode), else push',
    'max_q': 'the primitive whose Q map holds the larger maximum (ties: push)',
    'grasp': 'always grasp',
}


@dataclasses.dataclass(frozen=True)
class Method:
  name: str
  # One entry per fully convolutional network: (primitives it scores, camera views it sees).
  fcns: tuple[tuple[tuple[int, ...], tuple[int, ...]], ...]
  rule: str  # a key of RULES
  # Its networks read one heightmap fused from their views, the highest point per cell (MVP's
  # fusion of viewpoints), instead of one stream pair per view.
  fuse: bool = False
  # The rule compares Q maps weighted by CPG's suppression of actions that cannot act
  # (`suppression.py`): grasps whose fingers land on something, pushes with nothing ahead.
  suppress: bool = False
  # Camera poses the method needs (a camera it moves); choosing it sets scene.cameras to them.
  cameras: tuple[CameraConfig, ...] = ()

  def __post_init__(self):
    if self.rule not in RULES:
      raise ValueError(f'method {self.name!r}: rule {self.rule!r} is not one of {", ".join(RULES)}')
    scored = [p for prims, _ in self.fcns for p in prims]
    if not scored or len(scored) != len(set(scored)) or not set(scored) <= {PUSH, GRASP}:
      raise ValueError(f'method {self.name!r}: its networks must score each primitive at most '
                       f'once, got {scored}')

    if self.cameras and max(self.views) >= len(self.cameras):
      raise ValueError(f'method {self.name!r} reads views {self.views} of {len(self.cameras)} '
                       'cameras')

  @property
  def views(self) -> tuple[int, ...]:
    """Camera views its networks read, in order."""
    return tuple(sorted({v for _, views in self.fcns for v in views}))


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


register(Method('mvcoba', fcns=(((PUSH, GRASP), (0, 1)),), rule='change'))
register(Method('mvcoba_2fcn', fcns=(((PUSH,), (0,)), ((GRASP,), (1,))), rule='change'))
register(Method('vpg', fcns=(((PUSH,), (0,)), ((GRASP,), (0,))), rule='max_q'))
register(Method('grasp_only', fcns=(((GRASP,), (0,)),), rule='grasp'))
# MVP-like (Morrison et al. 2019): grasp only, one camera that looks from every one of its four
# poses before each grasp (the two fixed cameras' and two across the other axis), fused.
register(Method('mvp', fcns=(((GRASP,), (0, 1, 2, 3)),), rule='grasp', fuse=True,
                cameras=SceneConfig().cameras + (CameraConfig(pos=(0.0, 0.35, 0.65)),
                                                 CameraConfig(pos=(0.0, -0.35, 0.65)))))
# CPG (Collaborative Pushing-Grasping): VPG's two FCNs and max-Q, over suppressed Q maps.
register(Method('cpg', fcns=(((PUSH,), (0,)), ((GRASP,), (0,))), rule='max_q', suppress=True))
