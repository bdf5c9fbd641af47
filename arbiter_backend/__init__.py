"""arbiter-backend: latency tracker, differential-drive simulator and rosbridge endpoint.

Never imports Textual: a robot may carry only the backend.
"""

__version__ = "0.1.0"
