"""Services: what a running world serves to other programs, whatever the transport.

Owns the services (:mod:`~armfleet.services.world_services`: info, spawn, move, grip,
objects, pause/step, topics), their arguments and planning options, the wire values of
messages (:mod:`~armfleet.services.codec`), the protocol's names and limits
(:mod:`~armfleet.services.protocol`) and its errors. The live API
(:mod:`armfleet.remote`, ZeroMQ) and Foxglove (:mod:`armfleet.foxglove`) both serve these.

Rule: imports :mod:`armfleet.world` and the core below it; never a transport or a front
end.
"""
