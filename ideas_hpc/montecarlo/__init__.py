"""Monte Carlo over a designed swarm: declared dispersions and the per-sample flight.

* :mod:`~ideas_hpc.montecarlo.dispersions`: what each sample draws, in which
  order, how it perturbs the flyby and which store variables record it.
* :mod:`~ideas_hpc.montecarlo.sample`: the nominal design and one sample's flight.

The campaign kind that runs them on the engine is
:mod:`ideas_hpc.campaign.montecarlo`.
"""
