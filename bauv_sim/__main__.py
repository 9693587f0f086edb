"""``python -m bauv_sim ...``: the ``bauv`` command line (:func:`tasks.core.cli.main`), for an
environment whose scripts folder is not on the ``PATH``."""

from tasks.core.cli import main

if __name__ == "__main__":
    main()
