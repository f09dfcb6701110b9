"""Research-only pieces: collection loaders for benchmarks, trivial baselines.

Not shipped in the extension zip (blender_manifest.toml excludes this folder): the product never
imports it; `bench/` and `tests/` do.
"""
