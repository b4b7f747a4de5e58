"""A module of the user's own that the second extension imports, found on ``PYTHONPATH``
(the run's ``src/``) and not listed under ``extensions``: an edit of it must rerun every job, as
an edit of the extension does (``tests/test_stale_results.py``)."""

TITLE = "a second extension's study"
