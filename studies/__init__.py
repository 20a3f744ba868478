"""Studies that use the product rather than being part of it: the function-space study of the
spec's §2.4-2.5 (:mod:`~studies.function_space`), the random-design sampler of the
fuzz runs (:mod:`~studies.fuzz`) and the wind-tunnel measurements that ``simulate`` is validated
against (:mod:`~studies.wind_tunnel`). Nothing in the runtime modules imports them."""
