"""Shared numba kernels of the controllers: flat buffers, linear algebra, numba options and constants."""

from .buffers import BORROW, buffer_view, compiled_entry_point, pack_fields

__all__ = [
    "BORROW",
    "buffer_view",
    "compiled_entry_point",
    "pack_fields",
]
