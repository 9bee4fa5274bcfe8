"""Plugin modules used by the robustness tests (imported through a config's ``plugins:``)."""
