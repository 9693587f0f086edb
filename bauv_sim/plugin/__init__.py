"""The MuJoCo engine plugin ``bauv.hydro`` (C source ``hydro.c``, built at install)."""
