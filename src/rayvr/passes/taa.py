"""TAA pass (owned by the path-tracing engineer)."""
