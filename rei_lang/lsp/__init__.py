"""The REI language server (``rei-lsp``): live diagnostics, completion, navigation and outline.

Every rule comes from ``rei.lang.workspace.Workspace``, the checker ``rei-gen check`` uses;
this package only translates between the editor and that checker and must never check a
rule of its own.
"""
