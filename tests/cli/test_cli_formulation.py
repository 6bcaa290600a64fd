"""``lcpbench solve --formulation``: the form each step is handed in, and its errors."""

import json

from lcpbench.cli import main


def test_solve_formulation_json_says_what_ran(capsys):
    code = main(["solve", "--links", "30", "--theta", "150", "--height", "3", "--solver",
                 "lemke", "--formulation", "reactions", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 0 and d["converged"] and d["formulation"] == "reactions"


def test_solve_formulation_default_json_unchanged(capsys):
    main(["solve", "--links", "30", "--json"])
    assert "formulation" not in json.loads(capsys.readouterr().out)


def test_bad_formulation_is_one_line_and_status_2(capsys):
    for args in (["--formulation", "squares"], ["--solver", "lemke", "--formulation", "lifted"]):
        code = main(["solve", "--links", "30", *args])
        err = capsys.readouterr().err.strip()
        assert code == 2 and "\n" not in err and "formulation" in err
        assert "Traceback" not in err


# -- lcp FILE --formulation: a bare LCP has F1 and F4 (each +ruiz) -------------------------
def _npz(tmp_path, M, q):
    import numpy as np

    path = tmp_path / "p.npz"
    np.savez(path, M=np.asarray(M, float), q=np.asarray(q, float))
    return str(path)


def test_lcp_file_in_each_of_its_forms_gives_the_known_answer(tmp_path, capsys):
    import numpy as np

    # M = [[2, 1], [1, 2]], q = (-5, -6): both rows active, z = M⁻¹(−q) = (4/3, 7/3), w = 0
    path = _npz(tmp_path, [[2, 1], [1, 2]], [-5, -6])
    for form in ("gaps", "gaps+ruiz", "reactions", "reactions+ruiz", "F4r"):
        for solver in ("lemke", "pgs"):
            code = main(["lcp", path, "--solver", solver, "--settings", "high",
                         "--formulation", form, "--json"])
            d = json.loads(capsys.readouterr().out)
            assert code == 0 and d["status"] == "solved", (form, solver, d["message"])
            assert np.allclose(d["z"], [4 / 3, 7 / 3], atol=1e-7)
            assert d["formulation"] == {"F4r": "reactions+ruiz"}.get(form, form)


def test_lcp_file_forms_agree_with_enumeration_on_random_spd_problems(tmp_path, capsys):
    import numpy as np

    from lcpbench.model.formulations import solve_lcp_in
    from lcpbench.solvers.enumeration import enumerate_lcp

    rng = np.random.default_rng(3)
    for _ in range(5):
        A = rng.standard_normal((6, 6))
        M, q = A @ A.T + 0.5 * np.eye(6), rng.standard_normal(6)
        (exact,) = enumerate_lcp(M, q)  # the oracle: every active set (one answer: M SPD)
        for form in ("gaps+ruiz", "reactions", "reactions+ruiz"):
            sol = solve_lcp_in(M, q, "lemke", "high", form)
            assert sol.solved and np.allclose(sol.z, exact, atol=1e-9)
            assert np.allclose(sol.w, M @ sol.z + q)  # w belongs to the file's own problem


def test_lcp_file_forms_it_has_not_are_one_line_and_status_2(tmp_path, capsys):
    spd = _npz(tmp_path, [[2, 1], [1, 2]], [-5, -6])
    for args in ([spd, "--formulation", "heights"], [spd, "--formulation", "angles+ruiz"],
                 [spd, "--formulation", "squares"],
                 [_npz(tmp_path, [[1, 2], [0, 1]], [-1, -1]), "--solver", "lemke",
                  "--formulation", "reactions"]):
        code = main(["lcp", *args])
        err = capsys.readouterr().err.strip()
        assert code == 2 and "\n" not in err and "formulation" in err, err
        assert "Traceback" not in err


def test_lcp_file_best_is_the_backends_lcp_form_or_as_given(tmp_path, capsys):
    from lcpbench.model.formulations import best_formulations, parse_formulation

    path = _npz(tmp_path, [[2, 1], [1, 2]], [-5, -6])
    # the expected form is read from the committed table best resolves from (a wiring
    # check: which form ran; the answer itself is checked against z = (4/3, 7/3) above)
    best = best_formulations("high")
    for solver in ("qpsolvers-scs", "clarabel", "lemke"):
        main(["lcp", path, "--solver", solver, "--settings", "high", "--formulation", "best",
              "--json"])
        d = json.loads(capsys.readouterr().out)
        form = best.get(solver)
        want = form if form and parse_formulation(form).kind == "lcp" else "gaps"
        assert d["formulation"] == want


# -- select --formulation ---------------------------------------------------------------
def test_select_formulation_runs_and_names_the_form(tmp_path, capsys):
    args = ["select", "--force-tol", "1e-3", "--links", "20", "--solvers", "lemke",
            "--formulation", "reactions",
            "--store", str(tmp_path / "s.sqlite"), "--quiet", "--jobs", "1"]
    code = main([*args, "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 0 and d["backend"] == "lemke" and d["formulation"] == "reactions"
    assert main(args) == 0  # cached: the probes were stored as globalised@reactions
    out = capsys.readouterr().out.strip()
    assert "--formulation reactions:" in out and len(out.splitlines()) == 1


def test_select_formulation_a_backend_does_not_take_is_one_line_and_status_2(tmp_path, capsys):
    code = main(["select", "--links", "20", "--solvers", "lemke", "--formulation", "lifted",
                 "--store", str(tmp_path / "s.sqlite"), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "lifted" in err and "Traceback" not in err


def test_a_selection_in_a_formulation_is_solved_in_it(tmp_path):
    import lcpbench
    from lcpbench.bench.select import select_backend

    scene = lcpbench.ActuatorScene(theta=150, height=3.0, links=20)
    sel = select_backend(scene, force_tol=1e-3, candidates=["lemke"], settings=("default",),
                         formulation="gaps+ruiz", evidence=[], store=tmp_path / "s.sqlite")
    assert sel.backend == "lemke" and sel.formulation == "gaps+ruiz"
    res = lcpbench.solve(scene, solver=sel)
    assert res.converged and res.extra["formulation"] == "gaps+ruiz"


# -- what native code prints stays off stdout ------------------------------------------
def test_lcp_osqp_high_json_is_json_alone(tmp_path):
    """OSQP 1.1 prints "Polishing not needed ..." from C at `high` (polishing on) even
    when told verbose=False; `--json` output must stay one JSON document. Run in a
    process of its own: only there does C's stdout reach the real file descriptor 1."""
    import os
    import subprocess
    import sys

    import numpy as np
    import pytest

    pytest.importorskip("osqp")
    # M = [[2, 1], [1, 2]], q = (-5, -6): both rows active, z = M⁻¹(−q) = (4/3, 7/3)
    path = _npz(tmp_path, [[2, 1], [1, 2]], [-5, -6])
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    proc = subprocess.run([sys.executable, "-m", "lcpbench.cli", "lcp", path, "--solver",
                           "osqp", "--settings", "high", "--json"],
                          capture_output=True, text=True, timeout=120, env=env)
    assert proc.returncode == 0, proc.stderr
    d = json.loads(proc.stdout)  # nothing but the document on stdout
    assert d["solver"] == "osqp" and d["status"] == "solved"
    assert np.allclose(d["z"], [4 / 3, 7 / 3], atol=1e-7)
