"""mkdocs hook: the docstrings' Sphinx roles (:func:`x`, :class:`~a.b.C`) read as code.

mkdocstrings renders the docstrings as Markdown, where a role stays as text before its
code span; this drops the role (and the leading ``~`` of a shortened path) from the HTML.
"""

import re

ROLE = re.compile(r":(?:func|class|mod|meth|attr|data|exc|obj):<code>~?")


def on_page_content(html, **kwargs):
    return ROLE.sub("<code>", html)
