"""The LF-3PM metric written straight from its definitions, in float64:
full SVD of A, the least-squares solution, and the full eigen-decomposition of
the m x m matrix Phi. Slow by design; the fast Gram path is tested against it."""

import numpy as np


def reference_metric(A: np.ndarray, b: np.ndarray, w1: float = 0.5, w2: float = 0.5) -> dict:
    m, n = A.shape
    s = np.linalg.svd(A, compute_uv=False)
    sigma1 = s[-1]
    dx, *_ = np.linalg.lstsq(A, b, rcond=None)
    r = A @ dx - b
    xi = np.linalg.norm(dx) + np.linalg.norm(r) / sigma1
    phi = xi**2 * A @ A.T + np.outer(b, b)
    lam = np.linalg.eigvalsh(phi)  # ascending, m values
    lam = np.maximum(lam, 0.0)
    if m > n + 1:
        lam[: m - n - 1] = 0.0  # exactly zero in exact arithmetic (rank <= n + 1)

    def q(value):
        return np.sqrt(w1 * value + w2) / sigma1

    ata_eig = s[::-1] ** 2
    return {
        "sigma1": sigma1,
        "xi": xi,
        "q_min": q(lam[0]),
        "q_n": q(lam[m - n]),  # lambda_{m-n+1}, 1-based
        "q_max": q(lam[-1]),
        "zhang": ata_eig[0],
        "condition_number": s[0] / s[-1],
        "cov_trace": np.sum(1.0 / ata_eig),
        "step_norm": np.linalg.norm(dx),
        "residual_norm": np.linalg.norm(r),
    }
