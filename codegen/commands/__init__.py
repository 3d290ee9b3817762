"""One module per ``accugrid`` subcommand (see ``codegen.cli``)."""
