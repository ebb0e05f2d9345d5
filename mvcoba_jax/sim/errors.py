"""The one error class of the library's input."""


class Error(ValueError):
  """What mvcoba-jax cannot use, said in one line that names it (a file and line, a config key
  and its range, an argument): every error the library raises for its input is one of these
  (`mvcoba_jax.Error`), so a script catches one class."""
