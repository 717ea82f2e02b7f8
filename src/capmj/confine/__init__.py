"""Confinement of LLM-written task code (threat model in ``docs/security.md``).

The boundary is the operating system: generated code runs only in a jailed process
(:mod:`~capmj.confine.jail`: bubblewrap namespaces, read-only root, no capabilities, a clean
environment, rlimits; :mod:`~capmj.confine.seccomp`: no new process or program), forked per
episode by the jail's fork server (:mod:`~capmj.confine.forkserver`) as a task process
(:mod:`~capmj.confine.host`) and spoken to as validated data (:mod:`~capmj.confine.wire`) through a
:class:`~capmj.confine.proxy.ConfinedTask`.  In front of it stand early, explained rejections:
a static check of the names code may reference (:mod:`~capmj.confine.names`, from
:mod:`~capmj.confine.allowlist`) and, inside the jail, an audit hook (:mod:`~capmj.confine.guard`).
:mod:`~capmj.confine.manifest` keeps an accepted package what was accepted.  Importing this package
imports nothing.
"""
