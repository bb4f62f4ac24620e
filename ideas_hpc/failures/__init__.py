"""The failure model of a swarm (issue 41, docs/failure-model.md): the record and its
checks (:mod:`~ideas_hpc.failures.model`), an uncertain p_f (:mod:`~ideas_hpc.failures.prior`),
the survivor weights of the exact kernel (:mod:`~ideas_hpc.failures.weights`), the sums of
the proofs (:mod:`~ideas_hpc.failures.sums`) and the drawn failures
(:mod:`~ideas_hpc.failures.sampling`). One home for the designer, its bounds, the
validation and the Monte Carlo kind."""

from ideas_hpc.failures.model import FailureModel, as_model  # noqa: F401
from ideas_hpc.failures.prior import Prior  # noqa: F401
