"""The S2KF with Python models: for linear models it must reproduce the closed-form Kalman filter
(mean and covariance), with and without missing components; errors in a model reach Python and
leave the state untouched."""
import numpy as np
import pytest

import s2kf


def random_problem(seed, n=4, m=3):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n))
    prior_cov = a @ a.T + n * np.eye(n)
    prior_mean = rng.normal(size=n)
    h = rng.normal(size=(m, n))
    b = rng.normal(size=(m, m))
    r = b @ b.T + np.eye(m)
    y = h @ prior_mean + rng.normal(size=m) * 3
    return prior_mean, prior_cov, h, r, y


def kalman(mean, cov, h, r, y):
    s = h @ cov @ h.T + r
    gain = np.linalg.solve(s, h @ cov).T
    return mean + gain @ (y - h @ mean), cov - gain @ s @ gain.T


@pytest.mark.parametrize("samples", [lambda: s2kf.sample_set(4, 41), lambda: s2kf.sample_set(4, 40),
                                     lambda: s2kf.ukf_sample_set(4), lambda: s2kf.random_sample_set(4, 60, 9)])
def test_linear_update_equals_the_kalman_filter(samples):
    mean, cov, h, r, y = random_problem(1)
    filter = s2kf.SmartSamplingKalmanFilter(samples())
    calls = []

    def model(x):
        calls.append(x.shape)
        return x @ h.T

    state = s2kf.Gaussian(mean, cov)
    result = filter.update(state, model, y, r)
    assert result.ok and result.status == "ok" and result.observed == 3
    assert calls == [(filter.samples.count, 4)]  # one call with every sample
    expected_mean, expected_cov = kalman(mean, cov, h, r, y)
    np.testing.assert_allclose(state.mean, expected_mean, rtol=1e-11, atol=1e-11)
    np.testing.assert_allclose(state.covariance, expected_cov, rtol=1e-11, atol=1e-11)
    innovation = y - h @ mean
    nis = innovation @ np.linalg.solve(h @ cov @ h.T + r, innovation)
    assert result.nis == pytest.approx(nis, rel=1e-11)


def test_a_missing_component_is_dropped_not_zero_filled():
    mean, cov, h, r, y = random_problem(2)
    y[1] = np.nan  # never read where not observed
    state = s2kf.Gaussian(mean, cov)
    result = s2kf.SmartSamplingKalmanFilter(s2kf.sample_set(4, 41)).update(
        state, lambda x: x @ h.T, y, r, observed=[True, False, True])
    assert result.ok and result.observed == 2
    keep = [0, 2]
    expected_mean, expected_cov = kalman(mean, cov, h[keep], r[np.ix_(keep, keep)], y[keep])
    np.testing.assert_allclose(state.mean, expected_mean, rtol=1e-11, atol=1e-11)
    np.testing.assert_allclose(state.covariance, expected_cov, rtol=1e-11, atol=1e-11)


def test_six_steps_of_prediction_and_update_track_the_kalman_filter():
    mean, cov, h, r, _ = random_problem(3)
    rng = np.random.default_rng(4)
    a = np.eye(4) + 0.1 * rng.normal(size=(4, 4))
    q = 0.5 * np.eye(4)
    filter = s2kf.SmartSamplingKalmanFilter(4, 31)
    state = s2kf.Gaussian(mean, cov)
    for step in range(6):
        y = rng.normal(size=3) * 5
        # The sample-based prediction through a linear model is exact too.
        assert filter.predict(state, lambda x: x @ a.T, q) == "ok"
        mean, cov = a @ mean, a @ cov @ a.T + q
        np.testing.assert_allclose(state.covariance, cov, rtol=1e-10, atol=1e-10)
        assert filter.update(state, lambda x: x @ h.T, y, r).ok
        mean, cov = kalman(mean, cov, h, r, y)
        np.testing.assert_allclose(state.mean, mean, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(state.covariance, cov, rtol=1e-10, atol=1e-10)


def test_closed_form_predictions():
    state = s2kf.Gaussian(np.array([1.0, 2.0]), np.eye(2))
    filter = s2kf.SmartSamplingKalmanFilter(s2kf.ukf_sample_set(2))
    a = np.array([[1.0, 0.1], [0.0, 1.0]])
    assert filter.predict_linear(state, a, 0.01 * np.eye(2)) == "ok"
    np.testing.assert_allclose(state.mean, a @ [1.0, 2.0])
    np.testing.assert_allclose(state.covariance, a @ a.T + 0.01 * np.eye(2))
    filter.predict_random_walk(state, np.eye(2))
    np.testing.assert_allclose(state.covariance, a @ a.T + 1.01 * np.eye(2))


def test_lcd_sample_sets_have_exact_moments():
    s = s2kf.sample_set(5, 33)
    assert s.points.shape == (33, 5) and s.kind == "lcd"
    np.testing.assert_allclose(s.weights, 1 / 33)
    np.testing.assert_allclose(s.weights @ s.points, 0, atol=1e-13)
    np.testing.assert_allclose(s.points.T @ (s.weights[:, None] * s.points), np.eye(5), atol=1e-12)


def test_an_exception_in_the_model_reaches_python_and_keeps_the_state():
    mean, cov, h, r, y = random_problem(5)
    state = s2kf.Gaussian(mean, cov)

    def broken(x):
        raise ZeroDivisionError("my model broke")

    with pytest.raises(ZeroDivisionError, match="my model broke"):
        s2kf.SmartSamplingKalmanFilter(4, 41).update(state, broken, y, r)
    np.testing.assert_array_equal(state.mean, mean)
    np.testing.assert_array_equal(state.covariance, cov)


def test_a_model_result_of_the_wrong_shape_is_a_value_error():
    mean, cov, h, r, y = random_problem(6)
    with pytest.raises(ValueError, match=r"the measurement model's result must have shape \(L, M\) = \(41, 3\), got \(3, 41\)"):
        s2kf.SmartSamplingKalmanFilter(4, 41).update(s2kf.Gaussian(mean, cov), lambda x: (x @ h.T).T, y, r)


def test_a_non_finite_model_output_is_a_status_and_keeps_the_state():
    mean, cov, h, r, y = random_problem(7)
    state = s2kf.Gaussian(mean, cov)
    result = s2kf.SmartSamplingKalmanFilter(4, 41).update(state, lambda x: np.full((len(x), 3), np.nan), y, r)
    assert not result and result.status == "model output not finite"
    np.testing.assert_array_equal(state.mean, mean)


def test_samples_passed_to_the_model_are_read_only():
    mean, cov, h, r, y = random_problem(8)

    def writes(x):
        x[0, 0] = 1.0
        return x @ h.T

    with pytest.raises(ValueError, match="read-only"):
        s2kf.SmartSamplingKalmanFilter(4, 41).update(s2kf.Gaussian(mean, cov), writes, y, r)


@pytest.mark.parametrize("call, message", [
    (lambda f, s: f.update(s, lambda x: x, np.zeros(2), np.eye(3)), "R must be 2 x 2, got 3 x 3"),
    (lambda f, s: f.update(s, 3, np.zeros(2), np.eye(2)), None),
    (lambda f, s: f.update(s2kf.Gaussian(np.zeros(3), np.eye(3)), lambda x: x, np.zeros(2), np.eye(2)),
     "the state has dimension 3 but the filter's samples 2"),
    (lambda f, s: f.predict_random_walk(s, np.eye(3)), "Q must be 2 x 2, got 3 x 3"),
    (lambda f, s: f.update(s, lambda x: x, np.zeros(2), np.eye(2), observed=[True]),
     r"observed must be one bool per measurement component \(2\)"),
])
def test_bad_arguments_are_python_errors(call, message):
    filter = s2kf.SmartSamplingKalmanFilter(s2kf.ukf_sample_set(2))
    state = s2kf.Gaussian(np.zeros(2), np.eye(2))
    with pytest.raises((ValueError, TypeError), match=message):
        call(filter, state)


def test_impossible_sample_sets_are_value_errors():
    with pytest.raises(ValueError, match="needs at least 10 samples"):
        s2kf.sample_set(5, 7)
    with pytest.raises(ValueError, match=r"covariance must be 2 x 2, got 3 x 3"):
        s2kf.Gaussian(np.zeros(2), np.eye(3))
