"""The simulated tabletop: shapes, the MuJoCo scene, primitives, cameras, case files and the two
physics backends. Imports nothing of `mvcoba_jax` outside this package."""
