"""The file writers of the B-rep, together (as CadQuery keeps its exporters): ``step``, ``stl`` and
``threemf`` (the STEP reader is torus_cad.kernel.step_readback). Each writes the file it is given
atomically: a hidden temp file beside the path (torus_cad.runtime.files.atomic_path), checked whole,
then renamed onto it. A writer that fails says why when it can (torus_cad.runtime.files.write_failure):
a full file system or the file size limit is an OSError naming the path, anything else a KernelError.
A build's files are published together by torus_cad.outputs.output_set."""
