"""Tasks: the protocol, the entry-point registry, shared predicates and scene spawning."""
