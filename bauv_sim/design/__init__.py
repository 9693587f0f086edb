"""Design-time derivations of the BAUV model: what ``models/bauv`` holds, and why.

Nothing in this package acts on a running simulation. Its results are in the model's files and
``tests/bauv_sim/test_design.py`` checks them against those files:

* :mod:`bauv_sim.design.fluid`: the fluid coefficients and the crossflow damper from first
  principles, and the tow-test drag budget;
* :mod:`bauv_sim.design.ballast`: the ballast that makes the vehicle neutral and level;
* :mod:`bauv_sim.design.speed_table`: the speed table measured on the physics
  (``models/bauv/speed_table.csv``), its type and its loader (which missions read at set-up).
"""
