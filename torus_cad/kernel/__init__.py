"""The CAD kernel layer: OpenCascade (OCP) shapes and files made from the geometry layer's arrays.

Importing it quiets OpenCascade's default message printers to failures only, as importing cadquery
does: without it the STEP writer prints its transfer statistics on stdout (the build's own path
does not import cadquery, torus_cad.kernel.topology).
"""

from OCP.Message import Message, Message_Gravity

for _printer in Message.DefaultMessenger_s().Printers():
    _printer.SetTraceLevel(Message_Gravity.Message_Fail)
