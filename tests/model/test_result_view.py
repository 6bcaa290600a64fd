"""ContactResult's views (issue 15, item 4): summary(), _repr_html_, nodes().

Each view is checked against quantities computed independently of it: the
node positions by forward kinematics of the link angles, the wall height of
the scene, the sum of the reactions, and the contact set read off the gaps.
"""

from __future__ import annotations

import builtins
import re
from html.parser import HTMLParser

import numpy as np
import pytest

from lcpbench import ActuatorScene, solve
from lcpbench.problems.cantilever import CantileverScene


@pytest.fixture(scope="module")
def paper_default():
    return solve(ActuatorScene(theta=150, height=3.0, links=40))


@pytest.fixture(scope="module")
def channel():
    return solve(ActuatorScene(theta=150, height=3.0, links=40, channel=True))


def _hand_positions(res):
    """x, y of every node by summing the links a·(cos α, sin α) (independent of the model)."""
    a = res.scene.length / res.links
    x = np.concatenate(([0.0], np.cumsum(a * np.cos(res.alpha))))
    y = np.concatenate(([0.0], np.cumsum(a * np.sin(res.alpha))))
    return x, y


def test_nodes_dict_columns_match_independent_quantities(paper_default):
    res = paper_default
    t = res.nodes(frame=False)
    assert list(t) == ["node", "x", "y", "gap", "force", "contact"]
    n = res.links
    # the actuator's free nodes are the interior nodes 2..N (paper's numbering)
    np.testing.assert_array_equal(t["node"], np.arange(2, n + 1))
    x, y = _hand_positions(res)
    np.testing.assert_allclose(t["x"], x[1:n], rtol=0, atol=1e-12)
    np.testing.assert_allclose(t["y"], y[1:n], rtol=0, atol=1e-12)
    # the gap is the wall height minus the node's height
    np.testing.assert_allclose(t["gap"], res.scene.height - y[1:n], atol=1e-12)
    # the reactions add up to the total force
    assert t["force"].sum() == pytest.approx(res.total_force, rel=1e-12)
    # contact nodes carry force and touch the wall; the others carry (next to) none
    assert t["contact"].any()
    assert np.all(t["force"][t["contact"]] > 0)
    assert np.all(np.abs(t["gap"][t["contact"]]) < 1e-6 * res.scene.length)
    assert t["force"][~t["contact"]].sum() < 1e-3 * res.total_force
    assert all(len(v) == n - 1 for v in t.values())


def test_channel_table_has_both_walls(channel):
    t = channel.nodes(frame=False)
    assert {"gap_lower", "force_lower"} <= set(t)
    # the two walls are at ±h: the gaps add up to 2h at every node
    np.testing.assert_allclose(t["gap"] + t["gap_lower"], 2 * channel.scene.height,
                               atol=1e-12)
    assert t["force_lower"].sum() == pytest.approx(float(np.sum(channel.forces_lower)),
                                                   abs=1e-15)


def test_cantilever_free_nodes_run_to_the_tip():
    res = solve(CantileverScene(links=20))
    t = res.nodes(frame=False)
    np.testing.assert_array_equal(t["node"], np.arange(2, 22))  # nodes 2..N+1
    x, y = _hand_positions(res)
    np.testing.assert_allclose(t["x"][-1], x[-1], atol=1e-12)
    np.testing.assert_allclose(t["y"][-1], y[-1], atol=1e-12)


def test_nodes_without_pandas_is_a_dict_and_frame_true_says_why(paper_default, monkeypatch):
    real_import = builtins.__import__

    def no_pandas(name, *args, **kw):
        if name == "pandas" or name.startswith("pandas."):
            raise ImportError("no pandas here")
        return real_import(name, *args, **kw)

    monkeypatch.setattr(builtins, "__import__", no_pandas)
    assert isinstance(paper_default.nodes(), dict)
    with pytest.raises(ImportError, match="pip install pandas"):
        paper_default.nodes(frame=True)


def test_nodes_as_dataframe(paper_default):
    pd = pytest.importorskip("pandas")
    df = paper_default.nodes()
    assert isinstance(df, pd.DataFrame)
    assert df.index.name == "node"
    assert df["force"].sum() == pytest.approx(paper_default.total_force, rel=1e-12)


def test_summary_names_force_contact_nodes_and_verdict(paper_default):
    res = paper_default
    text = res.summary()
    lines = text.splitlines()
    assert len(lines) >= 6 and "\n" not in repr(res)
    # F in mN, to 6 significant digits, from the sum of the reactions
    assert f"{1e3 * float(np.sum(res.forces)):.6g} mN" in text
    # the contact nodes listed are the nodes whose gap closed (independent of R)
    t = res.nodes(frame=False)
    touching = t["node"][np.abs(t["gap"]) < 1e-6 * res.scene.length]
    listed = re.search(r"contact node\(s\): ([\d, -]+)", text).group(1)
    numbers = []
    for part in listed.split(", "):
        a, _, b = part.partition("-")
        numbers += list(range(int(a), int(b or a) + 1))
    assert numbers == touching.tolist()
    assert "converged           yes" in text or re.search(r"converged\s+yes", text)
    assert "θ = 150°" in text and "h = 3 mm" in text and f"N = {res.links}" in text


def test_summary_of_a_failed_solve_says_no_and_why():
    res = solve(ActuatorScene(theta=150, height=3.0, links=40), solver="pgs")
    if res.converged:  # pragma: no cover - PGS does not converge on a contact step
        pytest.skip("PGS converged here")
    assert re.search(r"converged\s+NO \(", res.summary())
    assert res.reason in res.summary()


class _Cells(HTMLParser):
    def __init__(self):
        super().__init__()
        self.tags, self.text = [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)

    def handle_data(self, data):
        self.text.append(data)


def test_repr_html_is_a_table_of_the_summary(paper_default):
    page = paper_default._repr_html_()
    p = _Cells()
    p.feed(page)
    assert p.tags.count("table") == 1 and p.tags.count("tr") == len(
        paper_default.summary().splitlines()) - 1
    flat = " ".join(p.text)
    assert f"{1e3 * paper_default.total_force:.6g} mN" in flat
