"""Model builders for scene files: one module per ``[model] kind`` (imported lazily)."""
