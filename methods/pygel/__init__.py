"""Adapters for the pygel backend (one module per task); the library is imported lazily."""
