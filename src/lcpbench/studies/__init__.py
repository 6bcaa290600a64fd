"""Studies built on the library call: several solves that answer one question.

- :mod:`.discretisation` — the Sec. III-D rule for N (``auto_links``);
- :mod:`.validation` — the cantilever of Sec. III-G against beam theory;
- :mod:`.continuation` — a line of scenes, each started from its neighbours;
- :mod:`.states` — the stable states a cold start and the loading path reach.
"""
