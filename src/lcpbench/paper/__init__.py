"""The paper, regenerated: its numbers as data, figure stages and the README.

``lcpbench reproduce`` runs :func:`lcpbench.paper.reproduce.reproduce`. The
package reads in the order of the data flow:

* :mod:`~lcpbench.paper.data`: every number quoted from the paper, keyed by
  figure, table or section, and the grids of a run (:class:`Plan`);
* :mod:`~lcpbench.paper.figures`: stages of the model alone (Figs. 5-8,
  Sec. III-G / Fig. 10, Fig. 24);
* :mod:`~lcpbench.paper.baseline_figures`: stages against the appendix's
  root-finding baseline (Figs. 26-27, Tables I-II) and the eq. (13) errata;
* :mod:`~lcpbench.paper.output` and :mod:`~lcpbench.paper.plots`: the CSV/JSON
  and PNG files of each stage (matplotlib is imported only inside the
  plotting functions);
* :mod:`~lcpbench.paper.markdown`, :mod:`~lcpbench.paper.readme_model`,
  :mod:`~lcpbench.paper.readme_baseline` and :mod:`~lcpbench.paper.readme`:
  the README that sets our numbers beside the paper's;
* :mod:`~lcpbench.paper.reproduce`: the orchestrator.
"""
