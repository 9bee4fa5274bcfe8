"""Adapters for the meshlab backend (one module per task); the library is imported lazily."""
