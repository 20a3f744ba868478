"""The design studio: a local web page to design a propeller by turning its parameters.

``torus-cad studio [CONFIG] [--port 8080] [--host 127.0.0.1]`` serves it (trame, with a VTK
view rendered on the server). Parameters panel generated from the parameter schema, a
kernel-free preview within a fraction of a second of every change, the exact OpenCascade
solid from a worker process when it is ready, readouts and downloads.
"""
