"""What generated event automata are written against: the records of queries, signals and
requirements (``records``, with ``load_generated``) and the complex-event patterns over
simulation time (``patterns``). The generated modules import these two by name (automata
format 5). It may import only the languages' models and reactivex: it is observation's floor.
"""
