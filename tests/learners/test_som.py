import numpy as np
import pytest

from somarm.learners._kernels import grid_distance, neighbourhood_row
from somarm.learners.som import (
    distances_from,
    grid_coordinates,
    grid_distances,
    grid_offsets,
    map_shape,
    neighbourhood,
    squared_distances,
    update,
    winners,
)


def test_grid_coordinates_row_major():
    np.testing.assert_array_equal(grid_coordinates((3,)), [[0, 0], [1, 0], [2, 0]])
    np.testing.assert_array_equal(grid_coordinates((2, 3)), [[0, 0], [0, 1], [0, 2], [1, 0], [1, 1], [1, 2]])


def test_grid_distance_is_euclidean():
    d = grid_distances(grid_coordinates((3, 3)))
    assert d[0, 1] == 1.0 and d[0, 4] == np.sqrt(2.0) and d[0, 8] == np.sqrt(8.0) and d[2, 6] == np.sqrt(8.0)
    np.testing.assert_array_equal(d, d.T)
    line = grid_distances(grid_coordinates((5,)))
    np.testing.assert_array_equal(line[2], [2, 1, 0, 1, 2])


@pytest.mark.parametrize("shape", [(7,), (4, 6), (1, 5)])
def test_distances_from_the_centre_are_the_rows_of_the_matrix_bit_for_bit(shape):
    grid = grid_coordinates(shape)
    matrix = grid_distances(grid)
    centres = np.array([[0, len(grid) - 1], [len(grid) // 2, 1]])
    np.testing.assert_array_equal(distances_from(grid, centres), matrix[centres])
    offsets = grid_offsets(shape)
    compiled = [[grid_distance(offsets, a, b) for b in range(len(grid))] for a in range(len(grid))]
    np.testing.assert_array_equal(np.array(compiled), matrix)


@pytest.mark.parametrize("width", [0.0, 0.5, 1.0, np.sqrt(2.0) - 1.0, 2.0, 3.7, 9.0, 1e300])
def test_the_compiled_neighbourhood_row_is_the_neighbourhood_of_the_distances_bit_for_bit(width):
    matrix = grid_distances(grid_coordinates((9, 7)))
    out = np.empty(63)
    for centre in (0, 31, 62):
        neighbourhood_row(grid_offsets((9, 7)), centre, width, out)
        np.testing.assert_array_equal(out, neighbourhood(matrix[centre], width))


def test_linear_neighbourhood_formula():
    d = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    np.testing.assert_allclose(neighbourhood(d, 2.0), [1, 2 / 3, 1 / 3, 0, 0])
    np.testing.assert_array_equal(neighbourhood(d, 0.0), [1, 0, 0, 0, 0])
    np.testing.assert_array_equal(neighbourhood(d, 3.0), [1, 0.75, 0.5, 0.25, 0])
    assert (neighbourhood(np.linspace(0, 50, 101), 20 * 0.37) >= 0).all()


def test_winner_by_squared_distance_lowest_index_on_ties():
    weights = np.array([[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]])
    np.testing.assert_array_equal(squared_distances(weights, np.array([[1.0, 1.0]])), [[2.0, 1.0, 2.0]])
    assert winners(weights, np.array([[1.2, 0.1]]))[0] == 1
    assert winners(weights, np.array([[1.5, 0.0]]))[0] == 1  # equidistant from units 1 and 2
    many = winners(weights, np.array([[[0.1, 0.0], [1.9, 5.0], [1.0, 0.0]]]))
    np.testing.assert_array_equal(many, [[0, 2, 1]])


def test_update_three_unit_map_planted_weights():
    weights = np.array([[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]])
    x = np.array([[1.25, 0.5]])
    update(weights, x, np.array([1]), 0.5, 1.0, grid_coordinates((3,)))  # psi = [0.5, 1, 0.5], rates [0.25, 0.5, 0.25]
    np.testing.assert_array_equal(weights[0], [[0.3125, 0.125], [1.125, 0.25], [1.8125, 0.125]])


def test_update_mask_and_batch_independence():
    rng = np.random.default_rng(0)
    weights = rng.random((3, 4, 2))
    before = weights.copy()
    x = rng.random((3, 2))
    grid = grid_coordinates((2, 2))
    update(weights, x, np.array([0, 3, 1]), 0.3, 1.0, grid, mask=np.array([True, False, True]))
    np.testing.assert_array_equal(weights[1], before[1])
    alone = before[2:3].copy()
    update(alone, x[2:3], np.array([1]), 0.3, 1.0, grid)
    np.testing.assert_array_equal(weights[2], alone[0])


@pytest.mark.parametrize("shape", [(0,), (3, 0), (1, 2, 3), "ab", (2.5,)])
def test_bad_map_shapes(shape):
    with pytest.raises(ValueError, match="input_shape"):
        map_shape("input_shape", shape)
