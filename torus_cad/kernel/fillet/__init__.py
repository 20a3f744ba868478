"""The root fillet along every blade-hub junction: the tries and the result (``root_fillet``), one
fillet in a child process and its repair (``one_fillet``), the blade bends too tight for the ball
(``tight_bends``), one filleted blade patterned for all (``pattern``) and the fillet's C0 faces
split (``continuity``)."""
