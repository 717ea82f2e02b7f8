"""Confinement of LLM-written task code (issue #25; threat model in ``docs/security.md``).

Three layers, each stopping what the one before might miss: :mod:`~capmj.confine.names` (a
static check of the names code may reference, from :mod:`~capmj.confine.allowlist`),
:mod:`~capmj.confine.guard` (an audit hook in the check worker) and :mod:`~capmj.confine.oslayer`
(network and mount namespaces, read-only file system).  :mod:`~capmj.confine.manifest` keeps an
accepted package what was accepted.  This package sits beside ``capmj.tasks`` and imports none
of capmj at import time.
"""
