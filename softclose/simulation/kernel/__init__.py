"""The C stroke kernel: its source (``_kernel.c``), the coefficient table it reads
(:mod:`.table`) and the ctypes binding that calls it (:mod:`.binding`).
"""
