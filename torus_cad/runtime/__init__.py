"""What every command shares while it runs, below every layer of the design (it imports only the
standard library, the errors and the tolerances): signals (``interrupts``), files written whole and
who owns them (``files``), which process is which (``processes``), calls that can hang or crash run
in a child (``isolation``), files a design names read as untrusted input (``input_files``), the
optional extras (``extras``), the CPUs (``cpus``), the pipeline's stages and their timer
(``stages``) and the terminal's progress display (``progress``)."""
