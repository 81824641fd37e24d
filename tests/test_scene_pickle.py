"""A Scene pickles to its validated declaration (what a sweep's Dask workers receive):
the copy declares the same system, derives the same objects, and the cache of what the
original derived (which may hold loaded code) does not travel."""

from __future__ import annotations

import pickle

import sympy as sp

from symmech.examples import car, pendulum_wall, rolling_ball, spinning_disk


def test_a_scene_round_trips_through_pickle():
    for scene in (car(), rolling_ball(), spinning_disk()):
        copy = pickle.loads(pickle.dumps(scene))
        assert copy is not scene
        assert copy.declaration == scene.declaration
        assert copy.name == scene.name
        assert [w.name for w in copy.walls] == [w.name for w in scene.walls]
        assert sp.Matrix(copy.mass_matrix()) == sp.Matrix(scene.mass_matrix())
        assert sp.Matrix(copy.forcing()) == sp.Matrix(scene.forcing())


def test_the_derived_cache_does_not_travel():
    scene = pendulum_wall()
    before = len(pickle.dumps(scene))
    scene.mass_matrix()
    scene.forcing()
    scene.impact_map(0)
    assert scene._cache  # something was derived
    assert len(pickle.dumps(scene)) == before
    copy = pickle.loads(pickle.dumps(scene))
    assert not copy._cache
    assert copy.impact_map(0).post_velocity == scene.impact_map(0).post_velocity
