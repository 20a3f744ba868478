"""What every command shares while it runs: signals (``interrupts``), files a design names read as
untrusted input (``input_files``), work refused before it starts (``budgets``), the pipeline's
stages and their timer (``stages``) and the terminal's progress display (``progress``)."""
