"""rangesynth: realistic range images and hypothesis verification on any Vulkan device.

The Rust crate does the work; this package hands it numpy arrays (docs/python.md).
"""

from ._rangesynth import (
    Error,
    Mesh,
    Renderer,
    Verifier,
    devices,
    read_range_image,
    render_scene,
    validation_messages,
    verify,
)

__all__ = [
    "Error",
    "Mesh",
    "Renderer",
    "Verifier",
    "devices",
    "read_range_image",
    "render_scene",
    "validation_messages",
    "verify",
]
