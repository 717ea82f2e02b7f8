"""capmj's built-in benchmark tasks A–J (CapRavens / LoHoRavens, thesis Table 5.1), one module each.

Every module exposes ``TASK``, an object following :class:`capmj.tasks.protocol.Task`: a seeded
scene generator whose goal text is derived from the spawned scene, Ravens-style oracle goals, and
a success predicate over the final settled state.  ``common`` holds the shared stack helpers.
"""
