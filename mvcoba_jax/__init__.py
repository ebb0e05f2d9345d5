"""mvcoba-jax: batched MuJoCo push-and-grasp learning in clutter and occlusion (MV-COBA)."""
__version__ = '0.1.0'
