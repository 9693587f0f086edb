"""The BAUV's manoeuvring model: Fossen's 6-DOF equations with forces identified from the full
MuJoCo vehicle, vectorised over Monte Carlo runs and stepped at a control tick (issue 27).

:class:`~bauv_sim.manoeuvring.model.ManoeuvringWorld` holds ``n`` independent vehicles;
``models/bauv/manoeuvring.json`` holds the identified tables, written by
``python models/bauv/tools/manoeuvring_id.py`` (which also validates the model against the full
one and writes the table in ``models/bauv/README.md``).
"""
