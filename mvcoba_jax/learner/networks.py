"""Pixel-wise push and grasp Q-networks as Flax NNX modules.

A network maps a state (per view a colour and a depth heightmap) and K rotation indices to Q maps
(B, 2, K, R, R), channel PUSH then GRASP. For rotation k the heightmaps are turned by -angle(k),
so that the primitive's yaw points along +x (col) for every k and the weights are shared across
rotations; one fully convolutional pass scores every pixel and its maps are turned back by
+angle(k). Only the requested rotations are computed: the learner asks for the executed one.
Turning a square map by a non-right angle cuts its corners: there the inputs read as missing
cells and the turned-back maps read Q = 0 (the zero fill of `geometry.rotate_images`), unless
`network.pad_to_diagonal` first pads the maps with missing cells to their diagonal.

One fully convolutional network (FCN): per used view a colour and a depth stream down to 1/4 of
the heightmap, concatenated over views, a trunk, a 1x1 head and bilinear upsampling to R x R.
"""
from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import optax
from flax import nnx

from mvcoba_jax import methods
from mvcoba_jax.config import DENSENET_GROWTH, NetworkConfig
from mvcoba_jax.sim.geometry import rotate_images, rotation_angle
from mvcoba_jax.sim.primitives import GRASP, PUSH

# The only input scaling, applied after rotation so that the zero fill stays a missing cell.
INPUT_NORMALISATION = {
    'color_mean': (0.485, 0.456, 0.406),  # colour in 0..1, ImageNet statistics
    'color_std': (0.229, 0.224, 0.225),
    'depth_scale': 0.1,  # m: depth / depth_scale
}
NO_ACTION = -1e9  # Q of a primitive a method cannot execute: max-Q never picks it

DENSENET121_BLOCKS = (6, 12, 24, 16)


class ResBlock(nnx.Module):
  """Pre-activation residual block: GroupNorm, relu, 3x3 conv, twice."""

  def __init__(self, cin: int, cout: int, dilation: int, groups: int, rngs: nnx.Rngs):
    self.norm1 = nnx.GroupNorm(cin, num_groups=groups, rngs=rngs)
    self.conv1 = nnx.Conv(cin, cout, (3, 3), kernel_dilation=dilation, rngs=rngs)
    self.norm2 = nnx.GroupNorm(cout, num_groups=groups, rngs=rngs)
    self.conv2 = nnx.Conv(cout, cout, (3, 3), kernel_dilation=dilation, rngs=rngs)
    self.skip = nnx.Conv(cin, cout, (1, 1), rngs=rngs) if cin != cout else None

  def __call__(self, x):
    h = self.conv1(nnx.relu(self.norm1(x)))
    h = self.conv2(nnx.relu(self.norm2(h)))
    return h + (self.skip(x) if self.skip is not None else x)


class Stream(nnx.Module):
  """One input (colour or depth) of one view down to 1/4 resolution.

  'small': a patchify conv (kernel = stride = stem_patch), ~4x faster on a CPU than a stride-2
  stem. 'densenet121': DenseNet's stem, a 7x7 stride-2 conv and a 3x3 stride-2 max pool.
  """

  def __init__(self, cin: int, cout: int, config: NetworkConfig, rngs: nnx.Rngs):
    self.pool = config.trunk == 'densenet121'
    if self.pool:
      self.conv = nnx.Conv(cin, cout, (7, 7), 2, rngs=rngs)
    else:
      patch = config.stem_patch
      self.conv = nnx.Conv(cin, cout, (patch, patch), patch, padding='VALID', rngs=rngs)
    self.norm = nnx.GroupNorm(cout, num_groups=config.groups, rngs=rngs)

  def __call__(self, x):
    x = nnx.relu(self.norm(self.conv(x)))
    return nnx.max_pool(x, (3, 3), (2, 2), padding='SAME') if self.pool else x


class SmallTrunk(nnx.Module):
  """One residual block per stage of `features[1:]` at stem resolution.

  Dilation doubles per stage instead of striding: the receptive field grows (default features:
  13 stem cells, 21 cm at 4 mm cells and 4 x 4 patches) while the maps keep their 1/4 resolution
  for the same cost; striding the last stage was only ~13% faster at R = 112.
  """

  def __init__(self, cin: int, config: NetworkConfig, rngs: nnx.Rngs):
    blocks = []
    for i, cout in enumerate(config.features[1:]):
      blocks.append(ResBlock(cin, cout, 2 ** i, config.groups, rngs))
      cin = cout
    self.blocks = nnx.List(blocks)
    self.out_features = cin

  def __call__(self, x, start: int = 0, stop: int | None = None):
    for block in self.blocks[start:stop]:
      x = block(x)
    return x


class DenseLayer(nnx.Module):
  """DenseNet bottleneck layer: GN, relu, 1x1 conv to 4 x growth, GN, relu, 3x3 conv to growth."""

  def __init__(self, cin: int, groups: int, rngs: nnx.Rngs):
    width = 4 * DENSENET_GROWTH
    self.norm1 = nnx.GroupNorm(cin, num_groups=groups, rngs=rngs)
    self.conv1 = nnx.Conv(cin, width, (1, 1), use_bias=False, rngs=rngs)
    self.norm2 = nnx.GroupNorm(width, num_groups=groups, rngs=rngs)
    self.conv2 = nnx.Conv(width, DENSENET_GROWTH, (3, 3), use_bias=False, rngs=rngs)

  def __call__(self, x):
    h = self.conv1(nnx.relu(self.norm1(x)))
    h = self.conv2(nnx.relu(self.norm2(h)))
    return jnp.concatenate([x, h], axis=-1)


class Transition(nnx.Module):
  """Between dense blocks: GN, relu, 1x1 conv halving the channels, 2x2 average pool."""

  def __init__(self, cin: int, groups: int, rngs: nnx.Rngs):
    self.norm = nnx.GroupNorm(cin, num_groups=groups, rngs=rngs)
    self.conv = nnx.Conv(cin, cin // 2, (1, 1), use_bias=False, rngs=rngs)

  def __call__(self, x):
    return nnx.avg_pool(self.conv(nnx.relu(self.norm(x))), (2, 2), (2, 2))


class DenseTrunk(nnx.Module):
  """DenseNet-121's body (dense blocks 6-12-24-16, growth 32), GroupNorm for BatchNorm so that
  no batch statistics enter the Q-learning state; trained from scratch. Output at 1/32."""

  def __init__(self, cin: int, config: NetworkConfig, rngs: nnx.Rngs):
    layers = []
    for i, depth in enumerate(DENSENET121_BLOCKS):
      if i:
        layers.append(Transition(cin, config.groups, rngs))
        cin //= 2
      for _ in range(depth):
        layers.append(DenseLayer(cin, config.groups, rngs))
        cin += DENSENET_GROWTH
    self.layers = nnx.List(layers)
    self.out_features = cin

  def __call__(self, x, start: int = 0, stop: int | None = None):
    for layer in self.layers[start:stop]:
      x = layer(x)
    return x


class FCN(nnx.Module):
  """Streams of `views`, fused by concatenation, a trunk and a 1x1 head with `outputs` maps.

  The streams have features[0] channels ('small') or DenseNet's 64 ('densenet121').
  """

  def __init__(self, views: tuple[int, ...], outputs: int, config: NetworkConfig,
               rngs: nnx.Rngs):
    self.views = views
    width = 64 if config.trunk == 'densenet121' else config.features[0]
    self.color = nnx.List([Stream(3, width, config, rngs) for _ in views])
    self.depth = nnx.List([Stream(1, width, config, rngs) for _ in views])
    trunk_class = DenseTrunk if config.trunk == 'densenet121' else SmallTrunk
    self.trunk = trunk_class(2 * len(views) * width, config, rngs)
    cout = self.trunk.out_features
    self.head_norm = nnx.GroupNorm(cout, num_groups=config.groups, rngs=rngs)
    self.head_hidden = nnx.Conv(cout, config.features[-1], (1, 1), rngs=rngs)
    self.head_out = nnx.Conv(config.features[-1], outputs, (1, 1), rngs=rngs)

  def encode(self, inputs: dict[int, jnp.ndarray], blocks: int = 0):
    """`inputs`: view -> (N, R, R, 4) normalised colour + depth; the streams, fused, through the
    trunk's first `blocks` blocks: (N, r, r, C) at the stem's resolution."""
    features = []
    for v, color, depth in zip(self.views, self.color, self.depth):
      features += [color(inputs[v][..., :3]), depth(inputs[v][..., 3:])]
    return self.trunk(jnp.concatenate(features, axis=-1), 0, blocks)

  def decode(self, x, blocks: int = 0):
    """The trunk after its first `blocks` blocks and the head: (N, r, r, outputs)."""
    x = self.head_hidden(nnx.relu(self.head_norm(self.trunk(x, blocks))))
    return self.head_out(nnx.relu(x))

  def __call__(self, inputs: dict[int, jnp.ndarray]):
    """`inputs` as `encode`'s; returns (N, R, R, outputs)."""
    return upsample(self.decode(self.encode(inputs)), inputs[self.views[0]].shape[1])


def upsample(maps, side: int):
  """(N, r, r, C) maps at the stem's resolution -> (N, side, side, C), bilinear."""
  # Always an enlargement, where antialiasing does nothing; stated, as ONNX's Resize needs it.
  return jax.image.resize(maps, maps.shape[:1] + (side, side) + maps.shape[3:], 'bilinear',
                          antialias=False)


def diagonal_padding(side: int, stride: int) -> int:
  """Cells added on each side of a `side` map so that its diagonal fits, rounded up so that the
  padded side is a multiple of the trunk's `stride` where it can be; 0 for stride 0 (no padding)."""
  if not stride:
    return 0
  pad = -(-(math.ceil(side * math.sqrt(2)) - side) // 2)
  return next((p for p in range(pad, pad + stride) if (side + 2 * p) % stride == 0), pad)


def _normalise(x):
  """(..., 4) raw colour (0..1) + depth (m) -> network input, per INPUT_NORMALISATION."""
  mean = jnp.array(INPUT_NORMALISATION['color_mean'] + (0.0,), x.dtype)
  scale = jnp.array(INPUT_NORMALISATION['color_std'] + (INPUT_NORMALISATION['depth_scale'],),
                    x.dtype)
  return (x - mean) / scale


def fuse_views(color, depth):
  """One view from several: (B, U, R, R, 3), (B, U, R, R) -> (B, 1, R, R, 3), (B, 1, R, R).

  The highest point per cell, with the colour of the views that see it there (averaged when
  several do); a view that saw nothing in a cell (colour and depth 0) lends it no colour.
  """
  top = jnp.max(depth, axis=1, keepdims=True)
  lends = ((depth >= top) & (jnp.sum(color, axis=-1) > 0)).astype(color.dtype)[..., None]
  fused = jnp.sum(color * lends, axis=1, keepdims=True) / jnp.maximum(
      jnp.sum(lends, axis=1, keepdims=True), 1.0)
  return fused, top


class QNetwork(nnx.Module):
  """The method's FCNs behind one call: Q maps (B, 2, K, R, R) for K rotations per state.

  A primitive the method has no network for scores NO_ACTION everywhere. A fusing method's
  networks see one view, `fuse_views` of its views.
  """

  def __init__(self, method: methods.Method, config: NetworkConfig, num_rotations: int,
               rngs: nnx.Rngs):
    self.num_rotations = num_rotations
    stride = 32 if config.trunk == 'densenet121' else config.stem_patch
    self.pad_stride = stride if config.pad_to_diagonal else 0
    self.shared_stages = config.shared_stages
    self.method = method  # its rule, views and primitives: what acts on these maps
    self.views = method.views
    self.fuse = method.fuse
    self.streams = (0,) if self.fuse else self.views  # the inputs each FCN reads, by view
    self.primitives = tuple(fcn.primitives for fcn in method.fcns)
    self.fcns = nnx.List([FCN((0,) if self.fuse else fcn.views, len(fcn.primitives), config, rngs)
                          for fcn in method.fcns])

  def __call__(self, color, depth, rotations=None):
    """`color` (B, V, R, R, 3) 0..1, `depth` (B, V, R, R) m; `rotations` (B, K) int rotation
    indices, default all num_rotations for every state."""
    b, _, side = color.shape[:3]
    if rotations is None:
      rotations = jnp.broadcast_to(jnp.arange(self.num_rotations), (b, self.num_rotations))
    k = rotations.shape[1]
    views = list(self.views)
    color, depth = color[:, views], depth[:, views]
    if self.fuse:
      color, depth = fuse_views(color, depth)
    x = jnp.concatenate([color, depth[..., None]], axis=-1)  # (B, U, R, R, 4)
    x = jnp.moveaxis(x, 1, -2).reshape(b, side, side, -1)
    angle = rotation_angle(rotations.reshape(-1), self.num_rotations)
    turns = self._turned_features if self.shared_stages else self._turned_heightmaps
    maps = {}
    for prims, out in zip(self.primitives, turns(x, k, angle)):
      maps.update({p: out[..., i] for i, p in enumerate(prims)})
    q = jnp.stack([maps[p] if p in maps else jnp.full((b * k, side, side), NO_ACTION, x.dtype)
                   for p in (PUSH, GRASP)], axis=1)
    return jnp.swapaxes(q.reshape(b, k, 2, side, side), 1, 2)

  def _inputs(self, x):
    """(N, S, S, U * 4) raw inputs -> the FCNs' inputs, view -> (N, S, S, 4) normalised."""
    x = _normalise(x.reshape(x.shape[:3] + (len(self.streams), 4)))
    return {v: x[..., i, :] for i, v in enumerate(self.streams)}

  def _turned_heightmaps(self, x, k, angle):
    """Per FCN its (B * K, R, R, P) maps: every turn of the heightmaps through the whole FCN."""
    x = _per_rotation(x, k)
    pad = diagonal_padding(x.shape[1], self.pad_stride)
    # normalised after the turn, so that the fill stays a missing cell
    return [turned(lambda t, fcn=fcn: fcn(self._inputs(t)), x, angle, pad) for fcn in self.fcns]

  def _turned_features(self, x, k, angle):
    """As `_turned_heightmaps`, the first `shared_stages` stages run once per state: their
    feature maps are turned, the rest of the FCN runs per turn, and its maps are turned back at
    the stem's resolution, then upsampled."""
    blocks, inputs, out = self.shared_stages - 1, self._inputs(x), []
    for fcn in self.fcns:
      f = fcn.encode(inputs, blocks)
      f = _per_rotation(f, k)
      pad = diagonal_padding(f.shape[1], 1 if self.pad_stride else 0)
      maps = turned(lambda t, fcn=fcn: fcn.decode(t, blocks), f, angle, pad)
      out.append(upsample(maps, x.shape[1]))
    return out


def _per_rotation(x, k: int):
  """(N, ...) -> (N * K, ...): each state's maps once per rotation, state-major as the angles."""
  return jnp.broadcast_to(x[:, None], (x.shape[0], k) + x.shape[1:]).reshape((-1,) + x.shape[1:])


def turned(fn, x, angle, pad: int):
  """`fn` of `x` (N, S, S, C) turned by -`angle` (N,), its (N, S', S', C') output turned back by
  +`angle`: `x` first padded with `pad` cells of 0 on each side, which are cropped off after."""
  side = x.shape[1]
  x = jnp.pad(x, ((0, 0), (pad, pad), (pad, pad), (0, 0)))
  return rotate_images(fn(rotate_images(x, -angle)), angle)[:, pad:pad + side, pad:pad + side]


def build_network(config: NetworkConfig, num_rotations: int, rngs: nnx.Rngs) -> QNetwork:
  """The Q-network of `config.method` with the `config.trunk` backbone."""
  return QNetwork(methods.get(config.method), config, num_rotations, rngs)


def executed_q(q_maps, primitive, row, col):
  """(B,) Q(s, a) of the executed actions from (B, 2, 1, R, R) maps of their rotation: the only
  entries the loss sees."""
  return q_maps[jnp.arange(q_maps.shape[0]), primitive, 0, row, col]


def huber_loss(pred, target, delta: float = 1.0):
  """Elementwise Huber loss; the caller reduces it (and may weight it for prioritised replay)."""
  return optax.losses.huber_loss(pred, target, delta=delta)
