"""Jinja2 templates for the program dialects, one folder per dialect (``krl/``, ``gcode/``).

Shipped as package data; ``TEMPLATE_DIR`` is where the built-in ones live. Users may point the
CLI's ``--templates`` at a copy of this folder.
"""

from pathlib import Path

__all__ = ["TEMPLATE_DIR"]

TEMPLATE_DIR = Path(__file__).resolve().parent
