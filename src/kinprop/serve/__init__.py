"""``kinprop serve``: a live design-propagation workbench in the browser.

:func:`create_app` builds the ASGI application (FastAPI) for a model; :func:`serve` runs it
with uvicorn. Needs the optional extra ``kinprop[serve]``.
"""

from __future__ import annotations

from kinprop.serve.api import create_app


def serve(app, host: str = "127.0.0.1", port: int = 8000) -> None:
    """Run ``app`` with uvicorn until interrupted."""
    import uvicorn

    uvicorn.run(app, host=host, port=port, log_level="warning")


__all__ = ["create_app", "serve"]
