"""The G-code dialect (RS274/NGC as LinuxCNC reads it): emitter and parser."""

__all__: list[str] = []
