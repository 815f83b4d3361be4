//! Importers for the palette formats other programs write (work in progress).
