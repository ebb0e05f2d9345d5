"""Configuration presets: `--config NAME` loads `mvcoba_jax.presets.NAME.get_config()`."""
