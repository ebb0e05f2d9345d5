"""The simulated tabletop: shapes, the MuJoCo scene, primitives, cameras, case files, occluder
regions and the physics backends. Imports nothing of `mvcoba_jax` outside this package."""
