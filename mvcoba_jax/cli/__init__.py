"""Command-line entry points (`mvcoba-train`, `mvcoba-eval`, `mvcoba-export`, `mvcoba-viz`,
`mvcoba-demo`): argument parsing and process set-up around the library."""
