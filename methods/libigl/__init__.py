"""Adapters for the libigl backend (one module per task); the library is imported lazily."""
