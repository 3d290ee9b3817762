"""The KUKA KRL dialect: emitter (program model to .src/.dat text) and parser."""

__all__: list[str] = []
