"""Studies: thin scripts that run a configuration through copi and write a docs page
(configuration -> library call -> report page). Their caches are result stores; what a
store does not hold (the wall time of the run that did the work) is kept beside it by
:func:`studies._common.kept_times`."""
