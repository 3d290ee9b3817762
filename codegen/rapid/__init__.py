"""ABB RAPID: the drilling module (``emit``), the reader and rewrite of existing modules
(``scan``, ``rewrite``), the cell section (``section``), RAPID names (``names``) and the plug-in
(``plugin.PLUGIN``, ``codegen.plugin.DialectPlugin``)."""

__all__: list[str] = []
