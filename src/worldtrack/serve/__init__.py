"""``worldtrack serve``: the floor plan in a browser, with everyone on it, live or for a finished run.

* :mod:`~worldtrack.serve.plan` — the scene as SVG-pixel JSON (walkable area, obstacles, entry
  regions, cameras and the floor each one sees), the metres → pixels transform, and which cameras
  show a person;
* :mod:`~worldtrack.serve.run` — a finished run (``tracks.csv`` + ``run.yaml`` + scene) as one
  timeline the page scrubs and plays;
* :mod:`~worldtrack.serve.live` — the shared map on Redis read as it is written, and camera status;
* :mod:`~worldtrack.serve.frames` — annotated camera frames as JPEG (``--frames``, off by default);
* :mod:`~worldtrack.serve.app` — the Starlette app: routes, websocket fan-out, the token gate;
* :mod:`~worldtrack.serve.server` — binding the port, the token rule, uvicorn;
* ``static/`` — the page itself: ``index.html``, ``style.css`` and JavaScript modules (``app.js`` starts,
  ``page.js`` plan and people, ``zoom.js``, ``timeline.js`` a finished run, ``live.js`` the live map); no
  build step, no CDN.

Needs the ``serve`` extra: ``pip install 'worldtrack[serve]'`` (Starlette, uvicorn, websockets).
"""
