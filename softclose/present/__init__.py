"""What a user sees: figures (the only matplotlib code), text and HTML tables of results,
progress lines, and the notebook explorer.
"""
