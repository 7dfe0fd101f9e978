"""The planner: graph search on a SOLM (front end), then trajectory optimisation
(back end). Front end: :mod:`lf3pm.planner.esdf` (signed distance field),
:mod:`lf3pm.planner.cost_map` (perception cost layer),
:mod:`lf3pm.planner.graph_search` (A* / Dijkstra)."""
