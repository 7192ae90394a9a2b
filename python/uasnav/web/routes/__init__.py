"""The web application's routers: one per page and one for the JSON API.

:func:`uasnav.web.app.create_app` includes them; each reads the shared
:class:`~uasnav.web.context.WebContext` through a dependency.
"""
